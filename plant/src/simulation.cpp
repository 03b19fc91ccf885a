#include "fullarm/plant/simulation.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <numbers>
#include <stdexcept>

#include "fullarm/plant/signals.hpp"

namespace fullarm::plant {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// A joint's model name without its "R_" side prefix ("R_EB" -> "EB").
std::string shortName(const std::string& name) {
  return name.starts_with("R_") ? name.substr(2) : name;
}

}  // namespace

CommandUnit commandUnit(const JointParams& joint) noexcept {
  if (joint.actuator.kind == ActuatorKind::kIdealTorque || joint.input_mode == InputMode::kTorqueLoop) {
    return CommandUnit::kNewtonMetre;
  }
  return CommandUnit::kVolt;
}

double SimulationResult::realTimeFactor() const noexcept {
  return simulated_s / std::max(wall_s, 1e-12);
}

double fullScaleCommand(const JointParams& joint, const arm::ArmModel& model) {
  if (joint.input_mode == InputMode::kValveVoltage) return 1.0 / joint.valve.amplifier_gain_per_v;
  return model.joints[static_cast<std::size_t>(model.jointIndex(joint.name))].limits.torque_nm;
}

CommandFunction makeCommand(const InputSignal& input, const arm::ArmModel& model,
                            const std::vector<JointParams>& joints, double duration_s) {
  const bool is_csv = input.name.size() > 4 && input.name.ends_with(".csv");
  if (is_csv) {
    CommandTable table = loadCommandCsv(input.name);
    std::vector<std::size_t> column_of(joints.size(), 0);
    for (std::size_t k = 0; k < joints.size(); ++k) {
      for (std::size_t c = 0; c < table.names.size(); ++c) {
        if (table.names[c] == "command_" + joints[k].name || table.names[c] == "command_" + shortName(joints[k].name)) {
          column_of[k] = c;
        }
      }
    }
    return [table = std::move(table), column_of](std::size_t k, double t) { return table.valueAt(column_of[k], t); };
  }
  SignalParams s;
  s.kind = parseSignalKind(input.name);
  if ((s.kind == SignalKind::kChirp || s.kind == SignalKind::kMultisine) && !(input.stop_hz > input.start_hz)) {
    throw std::invalid_argument(input.name + ": stop_hz = " + std::to_string(input.stop_hz) +
                                " Hz must be above start_hz = " + std::to_string(input.start_hz) + " Hz");
  }
  s.duration_s = duration_s;
  s.start_hz = input.start_hz;
  s.stop_hz = input.stop_hz;
  s.frequency_hz = input.frequency_hz;
  s.step_time_s = std::min(0.1, 0.1 * duration_s);
  std::vector<SignalParams> per_joint;
  for (const JointParams& p : joints) {
    SignalParams sj = s;
    sj.amplitude = input.amplitude.value_or(fullScaleCommand(p, model));
    per_joint.push_back(sj);
  }
  return [per_joint](std::size_t k, double t) { return signalValue(per_joint[k], t); };
}

SimulationResult simulate(const arm::ArmModel& model, const PlantConfig& config, const std::vector<JointParams>& joints,
                          const CommandFunction& command, double duration_s, double dt_s, core::Progress* progress) {
  ArmPlant plant;
  plant.configure(model, joints, model.defaultPosture(), config.user_arm, config.solver, config.seed);
  const int n = plant.numJoints();
  const auto periods = static_cast<long>(std::llround(duration_s / dt_s));
  SimulationResult r;
  r.traces.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    r.traces[static_cast<std::size_t>(k)].joint = plant.joint(k).name;
    JointTrace& tr = r.traces[static_cast<std::size_t>(k)];
    tr.command_unit = commandUnit(plant.joint(k));
    // The trace's whole memory, up front (no growth by doubling while the run goes on).
    const auto samples = static_cast<std::size_t>(periods + 1);
    for (std::vector<double>* column : {&tr.time_s, &tr.command, &tr.q_rad, &tr.qd_radps, &tr.tau_measured_nm,
                                        &tr.p_a_pa, &tr.p_b_pa, &tr.spool_fraction}) {
      column->reserve(samples);
    }
  }
  core::Progress& report = core::progressOrQuiet(progress);
  report.begin("plant simulate", static_cast<std::size_t>(periods));
  PlantCommand cmd = PlantCommand::zero(n);
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i <= periods; ++i) {
    const double t = static_cast<double>(i) * dt_s;
    for (int k = 0; k < n; ++k) cmd.command[k] = command(static_cast<std::size_t>(k), t);
    // Log the state at t with the command applied over [t, t + dt).
    for (int k = 0; k < n; ++k) {
      JointTrace& tr = r.traces[static_cast<std::size_t>(k)];
      const JointState s = plant.state(k);
      tr.time_s.push_back(t);
      tr.command.push_back(cmd.command[k]);
      tr.q_rad.push_back(s.q_rad);
      tr.qd_radps.push_back(s.qd_radps);
      tr.tau_measured_nm.push_back(plant.measurement(k).tau_nm);
      tr.p_a_pa.push_back(s.p_a_pa);
      tr.p_b_pa.push_back(s.p_b_pa);
      tr.spool_fraction.push_back(s.spool);
      tr.p_min_pa = std::min({tr.p_min_pa, s.p_a_pa, s.p_b_pa});
      tr.p_max_pa = std::max({tr.p_max_pa, s.p_a_pa, s.p_b_pa});
      tr.stop_overshoot_rad =
          std::max({tr.stop_overshoot_rad, s.q_rad - plant.joint(k).max_rad, plant.joint(k).min_rad - s.q_rad});
    }
    if (i == periods) break;
    if (!plant.step(dt_s, cmd).ok()) {
      r.solver_ok = false;
      r.solver_error = plant.lastError();
      break;
    }
    report.advance();
  }
  report.end(r.solver_ok ? "" : "the solver failed");
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.simulated_s = plant.time();
  r.stats = plant.stats();
  for (int k = 0; k < n; ++k) {
    const JointTrace& tr = r.traces[static_cast<std::size_t>(k)];
    const JointParams& p = plant.joint(k);
    r.pressures_ok = r.pressures_ok && tr.p_min_pa >= p.return_pressure_pa - kPressureMargin_pa &&
                     tr.p_max_pa <= p.supply_pressure_pa + kPressureMargin_pa;
    r.stops_held = r.stops_held && tr.stop_overshoot_rad * kRadToDeg <= kStopOvershootLimit_deg;
  }
  return r;
}

void writeTraceCsv(const JointTrace& trace, const std::filesystem::path& file) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
  out << "time_s," << (trace.command_unit == CommandUnit::kVolt ? "command_v" : "command_nm")
      << ",q_rad,qd_rad_s,tau_measured_nm,p_a_pa,p_b_pa,spool_fraction\n";
  out << std::setprecision(10);
  for (std::size_t i = 0; i < trace.time_s.size(); ++i) {
    // "+ 0.0" turns a negative zero (e.g. a quantised torque of 0 counts) into 0.
    out << trace.time_s[i] << ',' << trace.command[i] + 0.0 << ',' << trace.q_rad[i] << ',' << trace.qd_radps[i] << ','
        << trace.tau_measured_nm[i] + 0.0 << ',' << trace.p_a_pa[i] << ',' << trace.p_b_pa[i] << ','
        << trace.spool_fraction[i] + 0.0 << '\n';
  }
  if (!out) throw std::runtime_error(file.string() + ": write failed");
}

}  // namespace fullarm::plant
