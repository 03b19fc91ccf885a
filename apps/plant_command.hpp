#pragma once
// `fullarm plant simulate` and the plant step of `fullarm demo`.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <optional>
#include <string>

#include "cli_options.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// Options of `fullarm plant simulate`.
struct PlantSimulateOptions {
  core::Progress* progress = nullptr;  ///< where the run reports its progress (null: silent)
  std::string arm_config;              ///< arm model YAML (default: dts_master.yaml)
  std::string plant_config;            ///< plant YAML (default: dts_plant.yaml)
  std::string joint = "EB";            ///< joint to excite (short or model name)
  bool whole_arm = false;              ///< --arm: all 7 joints, the same command on each
  std::string input = "chirp";         ///< chirp | step | sine | multisine | <file>.csv
  double duration_s = 5.0;
  std::optional<double> amplitude;  ///< command units; default full scale
  double frequency_hz = 1.0;        ///< sine
  double start_hz = 0.5;            ///< chirp / multisine
  double stop_hz = 80.0;            ///< chirp / multisine
  std::string input_mode;           ///< override: valve_voltage | torque_loop
  double dt_s = 1e-3;               ///< control period
  std::string out_dir = "out/plant";
};

/// The most joint samples (duration / dt + 1, times the active joints) one run records: the
/// traces are kept in memory (8 doubles a sample, 64 MB per million samples) until the CSV files
/// and the report are written, so the run's memory is bounded before it starts. At 1 kHz: 2000 s
/// of one joint, 285 s of the 7-joint arm.
inline constexpr double kMaxTraceSamples = 2e6;

/// Adds `plant` with its `simulate` subcommand to `app`, its options declared in `table`;
/// returns the `simulate` subcommand.
CLI::App* addPlantCommand(CLI::App& app, PlantSimulateOptions& options, OptionTable& table);

/// Runs `fullarm plant simulate`: CSV log(s), summary.json, report.html.
/// @return 0 when the run passed (no solver failure, pressures within [return, supply] up to
///   the check-valve margin, stops not exceeded by more than 0.5 deg), 1 otherwise.
/// @throws core::ConfigError for bad input (an option's value, a run longer than
///   kMaxTraceSamples allows, an unreadable command table); OutputError when the output folder
///   cannot be written.
int runPlantSimulate(const PlantSimulateOptions& options);

/// Result of the demo's plant step.
struct PlantDemoStep {
  bool pass = false;
  std::string detail;
};

/// The demo step: a simulated chirp experiment on R_EB (0.5-80 Hz, 30 % of full valve
/// opening, 5 s at 1 kHz); writes `plant_chirp.csv` into `out_dir` and adds its section and the
/// `results.plant` keys to `report`.
PlantDemoStep runPlantDemoStep(const arm::ArmModel& model, const std::filesystem::path& out_dir,
                               reports::Report& report);

}  // namespace fullarm::app
