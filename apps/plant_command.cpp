#include "plant_command.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "cli_values.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "fullarm/plant/signals.hpp"

namespace fullarm::app {
namespace {

// Pressures may pass supply/return by what the check valves need to pass their flow.
constexpr double kPressureMargin_pa = 0.5e6;
constexpr double kStopLimit_deg = 0.5;
constexpr std::size_t kMaxChartPoints = 4000;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

// Per-joint trace of a run.
struct Trace {
  std::string joint;
  std::vector<double> t, u, q, qd, tau, pa, pb, spool;
  double p_min = 1e300;
  double p_max = -1e300;
  double overshoot_rad = 0.0;
};

struct RunResult {
  std::vector<Trace> traces;
  plant::SolverStats stats;
  bool solver_ok = true;
  std::string solver_error;
  double wall_s = 0.0;
  double simulated_s = 0.0;
};

double fullScale(const plant::JointParams& p, const arm::ArmModel& model) {
  if (p.input_mode == plant::InputMode::kValveVoltage) return 1.0 / p.valve.amplifier_gain_per_v;
  return model.joints[static_cast<std::size_t>(model.jointIndex(p.name))].limits.torque_nm;
}

RunResult simulate(const arm::ArmModel& model, const plant::PlantConfig& config,
                   const std::vector<plant::JointParams>& joints,
                   const std::function<double(std::size_t, double)>& command, double duration_s, double dt_s) {
  plant::ArmPlant plant;
  plant.configure(model, joints, model.defaultPosture(), config.user_arm, config.solver, config.seed);
  const int n = plant.numJoints();
  const auto periods = static_cast<long>(std::llround(duration_s / dt_s));
  RunResult r;
  r.traces.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) r.traces[static_cast<std::size_t>(k)].joint = plant.joint(k).name;
  plant::PlantCommand cmd = plant::PlantCommand::zero(n);
  const auto start = std::chrono::steady_clock::now();
  for (long i = 0; i <= periods; ++i) {
    const double t = static_cast<double>(i) * dt_s;
    for (int k = 0; k < n; ++k) cmd.command[k] = command(static_cast<std::size_t>(k), t);
    // Log the state at t with the command applied over [t, t + dt).
    for (int k = 0; k < n; ++k) {
      Trace& tr = r.traces[static_cast<std::size_t>(k)];
      const plant::JointState s = plant.state(k);
      tr.t.push_back(t);
      tr.u.push_back(cmd.command[k]);
      tr.q.push_back(s.q_rad);
      tr.qd.push_back(s.qd_radps);
      tr.tau.push_back(plant.measurement(k).tau_nm);
      tr.pa.push_back(s.p_a_pa);
      tr.pb.push_back(s.p_b_pa);
      tr.spool.push_back(s.spool);
      tr.p_min = std::min({tr.p_min, s.p_a_pa, s.p_b_pa});
      tr.p_max = std::max({tr.p_max, s.p_a_pa, s.p_b_pa});
      tr.overshoot_rad =
          std::max({tr.overshoot_rad, s.q_rad - plant.joint(k).max_rad, plant.joint(k).min_rad - s.q_rad});
    }
    if (i == periods) break;
    if (!plant.step(dt_s, cmd).ok()) {
      r.solver_ok = false;
      r.solver_error = plant.lastError();
      break;
    }
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.simulated_s = plant.time();
  r.stats = plant.stats();
  return r;
}

void writeCsv(const Trace& tr, const std::filesystem::path& file) {
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot open for writing");
  out << "time_s,command,q_rad,qd_rad_s,tau_measured_nm,p_a_pa,p_b_pa,spool\n";
  out << std::setprecision(10);
  for (std::size_t i = 0; i < tr.t.size(); ++i) {
    // "+ 0.0" turns a negative zero (e.g. a quantised torque of 0 counts) into 0.
    out << tr.t[i] << ',' << tr.u[i] + 0.0 << ',' << tr.q[i] << ',' << tr.qd[i] << ',' << tr.tau[i] + 0.0 << ','
        << tr.pa[i] << ',' << tr.pb[i] << ',' << tr.spool[i] + 0.0 << '\n';
  }
  if (!out) throw std::runtime_error(file.string() + ": write failed");
}

reports::Series series(const std::string& name, const std::vector<double>& x, const std::vector<double>& y,
                       double scale = 1.0) {
  reports::Series s;
  s.name = name;
  const std::size_t stride = std::max<std::size_t>(1, x.size() / kMaxChartPoints);
  for (std::size_t i = 0; i < x.size(); i += stride) {
    s.x.push_back(x[i]);
    s.y.push_back(y[i] * scale);
  }
  return s;
}

void addTraceCharts(reports::Section& section, const Trace& tr, const std::string& command_unit) {
  reports::XyChart motion;
  motion.title = shortJointName(tr.joint) + ": command and angle";
  motion.x_axis = {"Time", "s"};
  motion.y_axis = {"Value", command_unit + " / deg"};
  motion.series.push_back(series("command [" + command_unit + "]", tr.t, tr.u));
  motion.series.push_back(series("q [deg]", tr.t, tr.q, kRadToDeg));
  section.addLineChart(std::move(motion));
  reports::XyChart pressure;
  pressure.title = shortJointName(tr.joint) + ": chamber pressures";
  pressure.x_axis = {"Time", "s"};
  pressure.y_axis = {"Pressure", "MPa"};
  pressure.series.push_back(series("p_a", tr.t, tr.pa, 1e-6));
  pressure.series.push_back(series("p_b", tr.t, tr.pb, 1e-6));
  section.addLineChart(std::move(pressure));
  reports::XyChart torque;
  torque.title = shortJointName(tr.joint) + ": load-cell torque (as read: filtered, 12-bit)";
  torque.x_axis = {"Time", "s"};
  torque.y_axis = {"Torque", "N·m"};
  torque.series.push_back(series("tau measured", tr.t, tr.tau));
  section.addLineChart(std::move(torque));
}

void addStatsTable(reports::Section& section, const RunResult& r) {
  reports::Table t;
  t.caption = "CVODES statistics (BDF, dense direct solver, analytic Jacobian)";
  t.columns = {"Quantity", "Value"};
  t.rows = {{"Simulated time [s]", r.simulated_s},
            {"Wall time [s]", r.wall_s},
            {"Real-time factor", r.simulated_s / std::max(r.wall_s, 1e-12)},
            {"Steps", r.stats.steps},
            {"RHS evaluations", r.stats.rhs_evals},
            {"Jacobian evaluations", r.stats.jac_evals},
            {"Error-test failures", r.stats.err_test_fails},
            {"Nonlinear convergence failures", r.stats.nonlin_conv_fails},
            {"Re-initialisations", r.stats.reinits},
            {"Hard-stop events", r.stats.root_events}};
  section.addTable(std::move(t));
}

nlohmann::json statsJson(const RunResult& r) {
  return {{"simulated_s", r.simulated_s},
          {"wall_s", r.wall_s},
          {"real_time_factor", r.simulated_s / std::max(r.wall_s, 1e-12)},
          {"steps", r.stats.steps},
          {"rhs_evals", r.stats.rhs_evals},
          {"jac_evals", r.stats.jac_evals},
          {"err_test_fails", r.stats.err_test_fails},
          {"nonlin_conv_fails", r.stats.nonlin_conv_fails},
          {"reinits", r.stats.reinits},
          {"root_events", r.stats.root_events}};
}

}  // namespace

CLI::App* addPlantCommand(CLI::App& app, PlantSimulateOptions& o) {
  CLI::App* plant = app.add_subcommand("plant", "The hydraulic plant model of the DTS arm (SUNDIALS CVODES)");
  plant->require_subcommand(1);
  CLI::App* sim = plant->add_subcommand("simulate",
                                        "Drive one joint (or the whole arm) with a command signal; "
                                        "write a CSV log, summary.json and report.html");
  sim->add_option("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)")
      ->check(CLI::ExistingFile);
  sim->add_option("--plant-config", o.plant_config, "Plant YAML (default: config/dts_plant.yaml)")
      ->check(CLI::ExistingFile);
  sim->add_option("--joint", o.joint, "Joint to excite, e.g. EB or R_EB")->capture_default_str();
  sim->add_flag("--arm", o.whole_arm,
                "Run all 7 arm joints (the same command on each, or command_<joint> CSV columns)");
  sim->add_option("--input", o.input, "chirp | step | sine | multisine | <file>.csv (header time_s,command)")
      ->capture_default_str();
  sim->add_option("--duration", o.duration_s, "Simulated time [s]")->check(CLI::PositiveNumber)->capture_default_str();
  sim->add_option("--amplitude", o.amplitude,
                  "Signal amplitude in command units (V, or N m in torque-loop mode); default full scale");
  sim->add_option("--frequency", o.frequency_hz, "Sine frequency [Hz]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sim->add_option("--start-hz", o.start_hz, "Chirp start / multisine fundamental [Hz]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sim->add_option("--stop-hz", o.stop_hz, "Chirp stop / highest multisine harmonic [Hz]")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  sim->add_option("--input-mode", o.input_mode, "Override the joints' input mode")
      ->check(CLI::IsMember({"valve_voltage", "torque_loop"}));
  sim->add_option("--dt", o.dt_s, "Control period [s]")->check(CLI::Range(1e-5, 0.1))->capture_default_str();
  sim->add_option("--out", o.out_dir, "Output folder")->capture_default_str();
  return sim;
}

int runPlantSimulate(const PlantSimulateOptions& o) {
  const arm::ArmModel model = arm::loadArmModel(configPathOr(o.arm_config, arm::defaultArmModelPath));
  const plant::PlantConfig config =
      plant::loadPlantConfig(configPathOr(o.plant_config, plant::defaultPlantConfigPath), model);
  std::vector<plant::JointParams> joints;
  if (o.whole_arm) {
    joints = config.joints;
  } else {
    joints = {config.joints[static_cast<std::size_t>(plant::findPlantJoint(config, o.joint))]};
  }
  for (plant::JointParams& p : joints) {
    if (o.input_mode == "valve_voltage") p.input_mode = plant::InputMode::kValveVoltage;
    if (o.input_mode == "torque_loop") p.input_mode = plant::InputMode::kTorqueLoop;
  }
  if (o.stop_hz <= o.start_hz && (o.input == "chirp" || o.input == "multisine")) {
    throw core::ConfigError({}, "--stop-hz", "must be above --start-hz");
  }
  // The command: a generated signal scaled per joint, or a CSV table.
  std::function<double(std::size_t, double)> command;
  std::string description;
  const bool is_csv = o.input.size() > 4 && o.input.ends_with(".csv");
  plant::CommandTable table;
  std::vector<std::size_t> column_of(joints.size(), 0);
  if (is_csv) {
    table = plant::loadCommandCsv(o.input);
    for (std::size_t k = 0; k < joints.size(); ++k) {
      for (std::size_t c = 0; c < table.names.size(); ++c) {
        if (table.names[c] == "command_" + joints[k].name ||
            table.names[c] == "command_" + shortJointName(joints[k].name)) {
          column_of[k] = c;
        }
      }
    }
    command = [&table, &column_of](std::size_t k, double t) { return table.valueAt(column_of[k], t); };
    description = "command table " + o.input;
  } else {
    plant::SignalParams s;
    s.kind = plant::parseSignalKind(o.input);
    s.duration_s = o.duration_s;
    s.start_hz = o.start_hz;
    s.stop_hz = o.stop_hz;
    s.frequency_hz = o.frequency_hz;
    s.step_time_s = std::min(0.1, 0.1 * o.duration_s);
    std::vector<plant::SignalParams> per_joint;
    for (const plant::JointParams& p : joints) {
      plant::SignalParams sj = s;
      sj.amplitude = o.amplitude.value_or(fullScale(p, model));
      per_joint.push_back(sj);
    }
    command = [per_joint](std::size_t k, double t) { return plant::signalValue(per_joint[k], t); };
    description = o.input + " signal";
  }

  std::cout << "fullarm plant simulate: " << (o.whole_arm ? "whole arm" : joints[0].name) << ", " << description << ", "
            << o.duration_s << " s at " << 1.0 / o.dt_s << " Hz\n";
  const RunResult r = simulate(model, config, joints, command, o.duration_s, o.dt_s);

  std::filesystem::create_directories(o.out_dir);
  reports::Report report("plant simulate",
                         "Hydraulic plant: " + (o.whole_arm ? std::string("whole arm") : joints[0].name));
  bool pressures_ok = true;
  bool stops_ok = true;
  for (std::size_t k = 0; k < r.traces.size(); ++k) {
    const Trace& tr = r.traces[k];
    pressures_ok = pressures_ok && tr.p_min >= joints[k].return_pressure_pa - kPressureMargin_pa &&
                   tr.p_max <= joints[k].supply_pressure_pa + kPressureMargin_pa;
    stops_ok = stops_ok && tr.overshoot_rad * kRadToDeg <= kStopLimit_deg;
    const std::string name = o.whole_arm ? "plant_log_" + shortJointName(tr.joint) + ".csv" : "plant_log.csv";
    writeCsv(tr, std::filesystem::path(o.out_dir) / name);
    report.addFile(name);
  }
  const bool pass = r.solver_ok && pressures_ok && stops_ok;
  std::string headline;
  if (!r.solver_ok) {
    std::ostringstream text;
    text << "CVODES failed at t = " << std::setprecision(6) << r.simulated_s << " s: " << r.solver_error;
    headline = text.str();
  } else if (!pressures_ok) {
    headline = "A chamber pressure left [return, supply] by more than 0.5 MPa";
  } else if (!stops_ok) {
    headline = "A joint passed its hard stop by more than 0.5 deg";
  } else {
    std::ostringstream text;
    text << "Simulated " << std::setprecision(4) << r.simulated_s
         << " s; pressures within [return, supply], stops held";
    headline = text.str();
  }
  report.setVerdict(pass, headline);
  report.addHeadlineNumber("real_time_factor", "Real-time factor", r.simulated_s / std::max(r.wall_s, 1e-12), "");
  report.addHeadlineNumber("cvodes_steps", "CVODES steps", static_cast<double>(r.stats.steps), "");
  report.addHeadlineNumber("jacobian_evals", "Jacobian evaluations", static_cast<double>(r.stats.jac_evals), "");
  nlohmann::json joints_json = nlohmann::json::array();
  for (const Trace& tr : r.traces) {
    joints_json.push_back({{"name", tr.joint},
                           {"p_min_pa", tr.p_min},
                           {"p_max_pa", tr.p_max},
                           {"stop_overshoot_deg", tr.overshoot_rad * kRadToDeg}});
  }
  report.results()["plant"] = {{"input", o.input},         {"duration_s", o.duration_s}, {"dt_s", o.dt_s},
                               {"whole_arm", o.whole_arm}, {"solver", statsJson(r)},     {"joints", joints_json},
                               {"solver_ok", r.solver_ok}};
  reports::Section& section = report.addSection("Simulation");
  section.addParagraph("Plant: " + config.source.string() + ". Input: " + description +
                       ". CSV columns: time_s, command, q_rad, qd_rad_s, tau_measured_nm, p_a_pa, p_b_pa, spool "
                       "(state at time_s; command held over the following period).");
  addStatsTable(section, r);
  const std::string unit = joints[0].input_mode == plant::InputMode::kValveVoltage ? "V" : "N·m";
  for (const Trace& tr : r.traces) addTraceCharts(report.addSection("Joint " + tr.joint), tr, unit);
  report.write(o.out_dir);
  std::cout << headline << "\nReal-time factor " << r.simulated_s / std::max(r.wall_s, 1e-12) << ", " << r.stats.steps
            << " CVODES steps, " << r.stats.jac_evals
            << " Jacobians\nReport: " << (std::filesystem::absolute(o.out_dir) / "report.html").string() << "\n";
  return pass ? 0 : 1;
}

PlantDemoStep runPlantDemoStep(const arm::ArmModel& model, const std::filesystem::path& out_dir,
                               reports::Report& report) {
  const plant::PlantConfig config = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  const plant::JointParams joint = config.joints[static_cast<std::size_t>(plant::findPlantJoint(config, "EB"))];
  plant::SignalParams s;
  s.kind = plant::SignalKind::kChirp;
  s.amplitude = 0.3 * fullScale(joint, model);
  s.start_hz = 0.5;
  s.stop_hz = 80.0;
  s.duration_s = 5.0;
  const RunResult r = simulate(
      model, config, {joint}, [&s](std::size_t, double t) { return plant::signalValue(s, t); }, s.duration_s, 1e-3);
  std::filesystem::create_directories(out_dir);
  writeCsv(r.traces[0], out_dir / "plant_chirp.csv");
  report.addFile("plant_chirp.csv");
  PlantDemoStep step;
  step.pass = r.solver_ok;
  std::ostringstream detail;
  detail << "R_EB chirp 0.5-80 Hz, 5 s: real-time factor " << std::setprecision(3)
         << r.simulated_s / std::max(r.wall_s, 1e-12) << ", " << r.stats.steps << " CVODES steps";
  step.detail = r.solver_ok ? detail.str() : "CVODES failed: " + r.solver_error;
  report.results()["plant"] = {{"joint", joint.name}, {"input", "chirp"}, {"solver", statsJson(r)}};
  reports::Section& section = report.addSection("Plant: simulated chirp experiment on R_EB");
  section.addParagraph(
      "The hydraulic plant (config/dts_plant.yaml) driven by a 0.5-80 Hz linear chirp at 30 % of "
      "full valve opening, 1 kHz zero-order hold, as an identification experiment would record it.");
  addStatsTable(section, r);
  addTraceCharts(section, r.traces[0], "V");
  return step;
}

}  // namespace fullarm::app
