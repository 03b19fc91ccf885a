#include "plant_command.hpp"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <sstream>

#include "cli_values.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "fullarm/plant/simulation.hpp"
#include "output_files.hpp"
#include "result_tables.hpp"

namespace fullarm::app {
namespace {

constexpr std::size_t kMaxChartPoints = 4000;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;

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

void addTraceCharts(reports::Section& section, const plant::JointTrace& tr) {
  const std::string command_unit = tr.command_unit == plant::CommandUnit::kVolt ? "V" : "N·m";
  reports::XyChart motion;
  motion.title = shortJointName(tr.joint) + ": command and angle";
  motion.x_axis = {"Time", "s"};
  motion.y_axis = {"Value", command_unit + " / deg"};
  motion.series.push_back(series("command [" + command_unit + "]", tr.time_s, tr.command));
  motion.series.push_back(series("q [deg]", tr.time_s, tr.q_rad, kRadToDeg));
  section.addLineChart(std::move(motion));
  reports::XyChart pressure;
  pressure.title = shortJointName(tr.joint) + ": chamber pressures";
  pressure.x_axis = {"Time", "s"};
  pressure.y_axis = {"Pressure", "MPa"};
  pressure.series.push_back(series("p_a", tr.time_s, tr.p_a_pa, 1e-6));
  pressure.series.push_back(series("p_b", tr.time_s, tr.p_b_pa, 1e-6));
  section.addLineChart(std::move(pressure));
  reports::XyChart torque;
  torque.title = shortJointName(tr.joint) + ": load-cell torque (as read: filtered, 12-bit)";
  torque.x_axis = {"Time", "s"};
  torque.y_axis = {"Torque", "N·m"};
  torque.series.push_back(series("tau measured", tr.time_s, tr.tau_measured_nm));
  section.addLineChart(std::move(torque));
}

}  // namespace

CLI::App* addPlantCommand(CLI::App& app, PlantSimulateOptions& o, OptionTable& table) {
  CLI::App* plant = app.add_subcommand("plant", "The hydraulic plant model of the DTS arm (SUNDIALS CVODES)");
  plant->require_subcommand(1);
  CLI::App* sim = plant->add_subcommand("simulate",
                                        "Drive one joint (or the whole arm) with a command signal; "
                                        "write a CSV log, summary.json and report.html");
  OptionDeclarer declare(*sim, table);
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--plant-config", o.plant_config, "Plant YAML (default: config/dts_plant.yaml)");
  declare.name("--joint", o.joint, "Joint to excite, e.g. EB or R_EB");
  declare.flag("--arm", o.whole_arm, "Run all 7 arm joints (the same command on each, or command_<joint> CSV columns)");
  declare.name("--input", o.input, "chirp | step | sine | multisine | <file>.csv (header time_s,command)");
  declare.number("--duration", o.duration_s,
                 "Simulated time; a run records at most 2,000,000 joint samples (duration / dt x joints)",
                 {1e-3, 3600.0, "s"});
  declare.number("--amplitude", o.amplitude,
                 "Signal amplitude in command units (V, or N m in torque-loop mode); default full scale",
                 {0.0, 1000.0, "V or N m"});
  declare.number("--frequency", o.frequency_hz, "Sine frequency (below half the control rate)", {1e-3, 5000.0, "Hz"});
  declare.number("--start-hz", o.start_hz, "Chirp start / multisine fundamental", {1e-3, 5000.0, "Hz"});
  declare.number("--stop-hz", o.stop_hz, "Chirp stop / highest multisine harmonic (below half the control rate)",
                 {1e-3, 5000.0, "Hz"});
  declare.choice("--input-mode", o.input_mode, "Override the joints' input mode", {"valve_voltage", "torque_loop"});
  declare.number("--dt", o.dt_s, "Control period", {1e-5, 0.1, "s"});
  declare.folder("--out", o.out_dir, "Output folder")->capture_default_str();
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
  // Frequencies the control period can represent; the memory of the traces bounded up front.
  const double nyquist_hz = 0.5 / o.dt_s;
  const auto below_nyquist = [&](const char* option, double hz) {
    if (hz >= nyquist_hz) {
      throw core::ConfigError({}, option,
                              "is " + numberText(hz) + " Hz: expected below half the control rate (" +
                                  numberText(nyquist_hz) + " Hz at --dt " + numberText(o.dt_s) + " s)");
    }
  };
  if (o.input == "sine") below_nyquist("--frequency", o.frequency_hz);
  if (o.input == "chirp" || o.input == "multisine") below_nyquist("--stop-hz", o.stop_hz);
  const double samples = (std::round(o.duration_s / o.dt_s) + 1.0) * static_cast<double>(joints.size());
  if (samples > kMaxTraceSamples) {
    throw core::ConfigError({}, "--duration",
                            numberText(o.duration_s) + " s at --dt " + numberText(o.dt_s) + " s on " +
                                std::to_string(joints.size()) + " joint(s) is " + std::to_string(std::lround(samples)) +
                                " trace samples: expected at most 2000000 (about 130 MB of traces); shorten the run "
                                "or lengthen --dt");
  }
  plant::InputSignal input;
  input.name = o.input;
  input.amplitude = o.amplitude;
  input.frequency_hz = o.frequency_hz;
  input.start_hz = o.start_hz;
  input.stop_hz = o.stop_hz;
  plant::CommandFunction command;
  try {
    command = plant::makeCommand(input, model, joints, o.duration_s);
  } catch (const std::invalid_argument& e) {
    throw core::ConfigError({}, "--input", e.what());
  } catch (const std::runtime_error& e) {
    throw core::ConfigError(o.input, "--input", e.what());
  }
  const bool is_csv = o.input.size() > 4 && o.input.ends_with(".csv");
  const std::string description = is_csv ? "command table " + o.input : o.input + " signal";

  std::cout << "fullarm plant simulate: " << (o.whole_arm ? "whole arm" : joints[0].name) << ", " << description << ", "
            << o.duration_s << " s at " << 1.0 / o.dt_s << " Hz\n";
  const plant::SimulationResult r = plant::simulate(model, config, joints, command, o.duration_s, o.dt_s, o.progress);

  createOutputFolder(o.out_dir);
  reports::Report report("plant simulate",
                         "Hydraulic plant: " + (o.whole_arm ? std::string("whole arm") : joints[0].name));
  for (const plant::JointTrace& tr : r.traces) {
    const std::string name = o.whole_arm ? "plant_log_" + shortJointName(tr.joint) + ".csv" : "plant_log.csv";
    const std::filesystem::path file = std::filesystem::path(o.out_dir) / name;
    writeOutput(file, [&] { plant::writeTraceCsv(tr, file); });
    report.addFile(name);
  }
  const bool pass = r.passed();
  std::string headline;
  if (!r.solver_ok) {
    std::ostringstream text;
    text << "CVODES failed at t = " << std::setprecision(6) << r.simulated_s << " s: " << r.solver_error;
    headline = text.str();
  } else if (!r.pressures_ok) {
    headline = "A chamber pressure left [return, supply] by more than 0.5 MPa";
  } else if (!r.stops_held) {
    headline = "A joint passed its hard stop by more than 0.5 deg";
  } else {
    std::ostringstream text;
    text << "Simulated " << std::setprecision(4) << r.simulated_s
         << " s; pressures within [return, supply], stops held";
    headline = text.str();
  }
  report.setVerdict(pass, headline);
  report.addHeadlineNumber("real_time_factor", "Real-time factor", r.realTimeFactor(), "");
  report.addHeadlineNumber("cvodes_steps", "CVODES steps", static_cast<double>(r.stats.steps), "");
  report.addHeadlineNumber("jacobian_evals", "Jacobian evaluations", static_cast<double>(r.stats.jac_evals), "");
  nlohmann::json joints_json = nlohmann::json::array();
  for (const plant::JointTrace& tr : r.traces) {
    joints_json.push_back({{"name", tr.joint},
                           {"p_min_pa", tr.p_min_pa},
                           {"p_max_pa", tr.p_max_pa},
                           {"stop_overshoot_deg", tr.stop_overshoot_rad * kRadToDeg}});
  }
  ResultTable stats = solverStatsTable(r);
  report.results()["plant"] = {{"input", o.input},         {"duration_s", o.duration_s}, {"dt_s", o.dt_s},
                               {"whole_arm", o.whole_arm}, {"joints", joints_json},      {"solver_ok", r.solver_ok}};
  mergeJson(report.results()["plant"], stats.json);
  reports::Section& section = report.addSection("Simulation");
  section.addParagraph("Plant: " + config.source.string() + ". Input: " + description +
                       ". CSV columns: time_s, command_v (command_nm in N·m), q_rad, qd_rad_s, tau_measured_nm, "
                       "p_a_pa, p_b_pa, spool_fraction (state at time_s; command held over the following period).");
  section.addTable(std::move(stats.table));
  for (const plant::JointTrace& tr : r.traces) addTraceCharts(report.addSection("Joint " + tr.joint), tr);
  writeReport(report, o.out_dir);
  std::cout << headline << "\nReal-time factor " << r.realTimeFactor() << ", " << r.stats.steps << " CVODES steps, "
            << r.stats.jac_evals
            << " Jacobians\nReport: " << (std::filesystem::absolute(o.out_dir) / "report.html").string() << "\n";
  return pass ? 0 : 1;
}

PlantDemoStep runPlantDemoStep(const arm::ArmModel& model, const std::filesystem::path& out_dir,
                               reports::Report& report) {
  const plant::PlantConfig config = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  const plant::JointParams joint = config.joints[static_cast<std::size_t>(plant::findPlantJoint(config, "EB"))];
  plant::InputSignal input;
  input.name = "chirp";
  input.amplitude = 0.3 * plant::fullScaleCommand(joint, model);
  input.start_hz = 0.5;
  input.stop_hz = 80.0;
  constexpr double kDuration_s = 5.0;
  const plant::SimulationResult r = plant::simulate(
      model, config, {joint}, plant::makeCommand(input, model, {joint}, kDuration_s), kDuration_s, 1e-3);
  createOutputFolder(out_dir);
  writeOutput(out_dir / "plant_chirp.csv", [&] { plant::writeTraceCsv(r.traces[0], out_dir / "plant_chirp.csv"); });
  report.addFile("plant_chirp.csv");
  PlantDemoStep step;
  step.pass = r.solver_ok;
  std::ostringstream detail;
  detail << "R_EB chirp 0.5-80 Hz, 5 s: real-time factor " << std::setprecision(3) << r.realTimeFactor() << ", "
         << r.stats.steps << " CVODES steps";
  step.detail = r.solver_ok ? detail.str() : "CVODES failed: " + r.solver_error;
  ResultTable stats = solverStatsTable(r);
  report.results()["plant"] = {{"joint", joint.name}, {"input", "chirp"}};
  mergeJson(report.results()["plant"], stats.json);
  reports::Section& section = report.addSection("Plant: simulated chirp experiment on R_EB");
  section.addParagraph(
      "The hydraulic plant (config/dts_plant.yaml) driven by a 0.5-80 Hz linear chirp at 30 % of "
      "full valve opening, 1 kHz zero-order hold, as an identification experiment would record it.");
  section.addTable(std::move(stats.table));
  addTraceCharts(section, r.traces[0]);
  return step;
}

}  // namespace fullarm::app
