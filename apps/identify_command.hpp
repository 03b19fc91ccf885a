#pragma once
// `fullarm identify` and the identify step of `fullarm demo`.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cli_options.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// Options of `fullarm identify`.
struct IdentifyOptions {
  std::string io = "sim";    ///< the I/O back-end the experiments run on: sim | fakedaq | comedi | lcm
  std::string arm_config;    ///< --config (default: dts_master.yaml)
  std::string plant_config;  ///< --plant (default: dts_plant.yaml)
  std::string settings;      ///< --settings (default: identification.yaml)
  std::string joint = "EB";  ///< the driven joint (short or model name)
  std::string out_dir = "out/identify";
  std::string daq_config;  ///< --daq-config: the channel map of fakedaq and comedi (default: dts_daq.yaml)
  std::string hil_config;  ///< --hil-config: the loop configuration of fakedaq, comedi and lcm (default: hil.yaml)
  std::string lcm_url;     ///< --lcm-url: the plant node of lcm (empty: the default URL)
  /// Seed of the simulated sensors' noise (sim: experiment k uses seed + k; fakedaq: one arm for
  /// both); unset: 1. The real arm has no seed.
  std::optional<int> seed;
  double duration_s = 5.0;   ///< excitation time of each experiment
  double amplitude_v = 0.5;  ///< peak of the excitation added to the valve command
  /// --hold-angle: the driven joint's hold angle [rad] (sim: the posture's; a device moves the
  /// joint there before the experiments); unset: the default posture's (sim) or where the joint
  /// is (a device).
  std::optional<double> hold_angle_rad;
  /// --confirm-arm-motion: the workspace is clear for the move to --hold-angle on the real arm
  /// (--io comedi, or an LCM node serving it); required there, refused elsewhere.
  bool confirm_arm_motion = false;
  int threads = 2;                 ///< threads of the fit's simulations
  std::string start;               ///< identified.yaml whose model starts the fit (default: the plant's groups)
  std::vector<std::string> logs;   ///< recorded logs: all but the last fitted, the last held out
  std::string log_format = "csv";  ///< --log-format: the experiment logs written, csv | lcm
  bool log_format_given = false;   ///< --log-format was on the command line
  std::string command_line;        ///< the command as typed (recorded in LCM logs)
  core::Progress* progress = nullptr;
};

/// Adds `identify` to `app`.
CLI::App* addIdentifyCommand(CLI::App& app, IdentifyOptions& options, OptionTable& table);

/// Runs `fullarm identify`: the experiment logs, identified.yaml, summary.json, report.html.
/// @return 0 when the identified model passes its validation on the held-out experiment, 1 otherwise.
/// @throws core::ConfigError for bad input (also a malformed log); OutputError when the output
///   folder cannot be written.
int runIdentify(const IdentifyOptions& options);

/// Result of the demo's identify step.
struct IdentifyDemoStep {
  bool pass = false;
  std::string detail;
};

/// The demo step: `fullarm identify` on the simulated elbow with the default settings, its files
/// in `out_dir`/identify and its section and `results.identify` keys in `report`.
IdentifyDemoStep runIdentifyDemoStep(const std::filesystem::path& out_dir, reports::Report& report,
                                     core::Progress& progress);

}  // namespace fullarm::app
