// fullarm: the one command-line program. Exit codes: 0 success and a passing verdict,
// 1 a failing verdict, 2 bad input (command line, configuration) or an I/O error.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <optional>

#include "arm_summary.hpp"
#include "cli_values.hpp"
#include "fullarm/arm/arm_scaling.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/reports/report.hpp"
#include "haptics_command.hpp"
#include "plant_command.hpp"
#include "run_command.hpp"
#include "tune_command.hpp"
#include "validate_command.hpp"

namespace fullarm::app {
namespace {

constexpr int kExitFail = 1;
constexpr int kExitBadInput = 2;
constexpr int kReachSamples = 20000;

// Options shared by every command that loads an arm model.
struct ArmOptions {
  std::string config;
  std::string arm_size_file;
  std::optional<double> upper_arm_m;
  std::optional<double> forearm_m;
  std::optional<double> hand_m;
  std::optional<double> radius_scale;

  void add(CLI::App& cmd) {
    cmd.add_option("--config", config, "Arm model YAML (default: the installed config/dts_master.yaml)")
        ->check(CLI::ExistingFile);
    cmd.add_option("--arm-size", arm_size_file, "YAML with arm_size: segment lengths of a user's arm")
        ->check(CLI::ExistingFile);
    cmd.add_option("--upper-arm-length", upper_arm_m, "Upper-arm length [m] (overrides --arm-size)")
        ->check(CLI::PositiveNumber);
    cmd.add_option("--forearm-length", forearm_m, "Forearm length [m] (overrides --arm-size)")
        ->check(CLI::PositiveNumber);
    cmd.add_option("--hand-length", hand_m, "Hand length, wrist to hand point [m] (overrides --arm-size)")
        ->check(CLI::PositiveNumber);
    cmd.add_option("--link-radius-scale", radius_scale, "Factor on every link capsule radius")
        ->check(CLI::PositiveNumber);
  }

  arm::ArmModel load() const {
    arm::ArmModel model = arm::loadArmModel(configPathOr(config, arm::defaultArmModelPath));
    arm::ArmSize size;
    if (!arm_size_file.empty()) size = arm::loadArmSize(arm_size_file);
    if (upper_arm_m) size.upper_arm_length_m = upper_arm_m;
    if (forearm_m) size.forearm_length_m = forearm_m;
    if (hand_m) size.hand_length_m = hand_m;
    if (radius_scale) size.link_radius_scale = radius_scale;
    if (size.upper_arm_length_m || size.forearm_length_m || size.hand_length_m || size.link_radius_scale) {
      model = arm::scaleArm(model, size);
    }
    return model;
  }
};

int runArmShow(const ArmOptions& options, const std::string& q_text, const std::string& out_dir) {
  const arm::ArmModel model = options.load();
  const Eigen::VectorXd q = q_text.empty() ? model.defaultPosture() : parseJointVector(q_text, model, "--q");
  const ArmSummary summary = summarizeArm(model, q, kReachSamples);
  printArmSummary(model, summary, std::cout);
  if (!out_dir.empty()) {
    reports::Report report("arm show", "DTS master arm model: " + model.name);
    report.setVerdict(summary.holds_itself,
                      summary.holds_itself ? "The model is valid and can hold itself against gravity at the posture"
                                           : "Gravity torques at the posture exceed a joint torque limit");
    addArmToReport(model, summary, report);
    report.write(out_dir);
    std::cout << "\nReport: " << (std::filesystem::absolute(out_dir) / "report.html").string() << "\n";
  }
  return summary.holds_itself ? 0 : kExitFail;
}

int runDemo(const ArmOptions& options, const std::string& out_dir, int validate_samples) {
  const std::filesystem::path controllers_gains_path = controllers::defaultGainsConfigPath();
  struct Step {
    const char* name;
    const char* status;
    const char* detail;
  };
  std::cout << "fullarm demo: simulated DTS, in-process transport, no hardware, no network.\n\n";
  std::cout << "[1/7] DTS arm model\n";
  const arm::ArmModel model = options.load();
  const ArmSummary summary = summarizeArm(model, model.defaultPosture(), kReachSamples);
  printArmSummary(model, summary, std::cout);

  std::cout << "\n[2/7] Simulated chirp experiment on one joint (hydraulic plant)\n";
  reports::Report report("demo", "fullarm demo");
  // The pipeline overview comes first in the report; its table is filled once the steps ran.
  reports::Section& pipeline = report.addSection("Pipeline");
  const PlantDemoStep plant_step = runPlantDemoStep(model, out_dir, report);
  std::cout << "  " << plant_step.detail << "\n";
  std::cout << "\n[4/7] Tune the admittance controller (NLopt, all 7 joints)\n";
  const TuneDemoStep tune_step = runTuneDemoStep(model, out_dir, report);
  std::cout << "  " << tune_step.detail << "\n";
  std::cout << "\n[5/7] Validate stability (linear checks + Monte-Carlo of nonlinear closed-loop runs)\n";
  const ValidateDemoStep validate_step = runValidateDemoStep(
      model, tune_step.gains_file.empty() ? controllers_gains_path : tune_step.gains_file, validate_samples, report);
  std::cout << "  " << validate_step.detail << "\n";
  std::cout << "\n[6/7] Haptic rendering at the valve opening (SNCH search, full-arm vs hand-only)\n";
  const HapticsDemoStep haptics_step = runHapticsDemoStep(model, out_dir, report);
  std::cout << "  " << haptics_step.detail << "\n";
  const Step steps[] = {
      {"DTS arm model", summary.holds_itself ? "done" : "failed", "kinematics, dynamics, reach, gravity load"},
      {"Simulated chirp experiment (plant)", plant_step.pass ? "done" : "failed", plant_step.detail.c_str()},
      {"Identify a joint", "not built yet", "needs the identification module (issue: Identification)"},
      {"Tune the admittance controller", tune_step.pass ? "done" : "failed", tune_step.detail.c_str()},
      {"Validate stability", validate_step.pass ? "done" : "failed", validate_step.detail.c_str()},
      {"Haptic rendering at the valve opening", haptics_step.pass ? "done" : "failed", haptics_step.detail.c_str()},
      {"Valve study, full-arm vs hand-only", "not built yet",
       "needs the virtual technician and the study protocol (the rendering itself is step 6)"},
  };
  std::cout << "\n";
  for (int i = 2; i < 7; ++i) {
    if (i == 3 || i == 4 || i == 5) continue;  // the tune, validate and haptics steps printed their own lines
    std::cout << "[" << i + 1 << "/7] " << steps[i].name << ": " << steps[i].status << " (" << steps[i].detail << ")\n";
  }

  const bool demo_pass =
      summary.holds_itself && plant_step.pass && tune_step.pass && validate_step.pass && haptics_step.pass;
  report.setVerdict(demo_pass, demo_pass               ? "Every step that exists passed (5 of 7 steps built)"
                               : !summary.holds_itself ? "The arm model step failed"
                               : !plant_step.pass      ? "The plant step failed"
                               : !tune_step.pass       ? "The tune step failed"
                               : !validate_step.pass   ? "The validate step failed"
                                                       : "The haptics step failed");
  nlohmann::json list = nlohmann::json::array();
  reports::Table table;
  table.caption = "Demo steps";
  table.columns = {"Step", "Status", "Detail"};
  for (const Step& step : steps) {
    list.push_back({{"name", step.name}, {"status", step.status}, {"detail", step.detail}});
    table.rows.push_back({step.name, step.status, step.detail});
  }
  report.results()["steps"] = list;
  pipeline.addTable(std::move(table));
  addArmToReport(model, summary, report);
  report.write(out_dir);
  std::cout << "\nReport: " << (std::filesystem::absolute(out_dir) / "report.html").string() << "\n";
  return demo_pass ? 0 : kExitFail;
}

}  // namespace
}  // namespace fullarm::app

namespace {

int runMain(int argc, char** argv) {
  using namespace fullarm;
  CLI::App app{
      "fullarm: hardware-in-the-loop test bench and controller design toolkit for full-arm haptics on the "
      "Sarcos DTS master arm"};
  app.set_version_flag("--version", std::string(reports::fullarmVersion()));
  app.require_subcommand(1);

  app::ArmOptions arm_options;
  CLI::App* arm_cmd = app.add_subcommand("arm", "The DTS master arm model");
  arm_cmd->require_subcommand(1);
  CLI::App* show = arm_cmd->add_subcommand("show", "Print the chain, limits, link lengths, mass, reach and hand pose");
  arm_options.add(*show);
  std::string q_text;
  std::string show_out;
  show->add_option("--q", q_text, "Posture: joint angles [rad], e.g. \"0,-0.3,0,1.57,0,0,0\" (default posture)");
  show->add_option("--out", show_out, "Write summary.json and report.html to this folder");

  app::ArmOptions demo_options;
  CLI::App* demo = app.add_subcommand("demo", "Run the whole story on the simulated DTS and write a report");
  demo_options.add(*demo);
  std::string demo_out = "out/demo";
  demo->add_option("--out", demo_out, "Output folder")->capture_default_str();
  int demo_validate_samples = 300;
  demo->add_option("--validate-samples", demo_validate_samples, "Monte-Carlo runs per joint of the validate step")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();

  app::TuneOptions tune_options;
  CLI::App* tune = app::addTuneCommand(app, tune_options);

  app::PlantSimulateOptions plant_options;
  CLI::App* plant_simulate = app::addPlantCommand(app, plant_options);

  app::ValidateOptions validate_options;
  CLI::App* validate = app::addValidateCommand(app, validate_options);
  app::HapticsQueryOptions haptics_options;
  CLI::App* haptics_query = app::addHapticsCommand(app, haptics_options);
  app::RunCommandOptions run_options;
  CLI::App* run = app::addRunCommand(app, run_options);
  app::ReplayCommandOptions replay_options;
  CLI::App* replay = app::addReplayCommand(app, replay_options);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : app::kExitBadInput;
  }
  try {
    if (show->parsed()) return app::runArmShow(arm_options, q_text, show_out);
    if (demo->parsed()) return app::runDemo(demo_options, demo_out, demo_validate_samples);
    if (plant_simulate->parsed()) return app::runPlantSimulate(plant_options);
    if (validate->parsed()) return app::runValidate(validate_options);
    if (tune->parsed()) return app::runTune(tune_options);
    if (haptics_query->parsed()) return app::runHapticsQuery(haptics_options);
    if (run->parsed()) {
      std::string command_line = "fullarm";
      for (int i = 1; i < argc; ++i) command_line.append(" ").append(argv[i]);
      return app::runRun(run_options, command_line);
    }
    if (replay->parsed()) return app::runReplay(replay_options);
  } catch (const core::ConfigError& e) {
    std::cerr << "fullarm: error: " << e.what() << "\n";
    return app::kExitBadInput;
  } catch (const std::exception& e) {
    std::cerr << "fullarm: error: " << e.what() << "\n";
    return app::kExitBadInput;
  }
  return app::kExitBadInput;
}

}  // namespace

int main(int argc, char** argv) {
  // Anything that escapes the commands (CLI11 set-up, out of memory) still gets a message and
  // the bad-input exit code rather than std::terminate.
  try {
    return runMain(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "fullarm: error: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "fullarm: error: unknown exception\n";
  }
  return 2;
}
