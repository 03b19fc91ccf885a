#pragma once
// `fullarm tune` and the tune step of `fullarm demo`.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_options.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/design/tune_arm.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// Options of `fullarm tune`: the files, the output folder, and the tuning's budget and switches.
struct TuneOptions {
  std::string arm_config;         ///< arm model YAML (default: dts_master.yaml)
  std::string plant_config;       ///< --plant (default: dts_plant.yaml)
  std::string gains;              ///< starting gains (default: dts_tune_start.yaml); B_o and filters are kept
  std::string validation_config;  ///< user model and uncertainty ranges (default: dts_validation.yaml)
  std::string out_dir = "out/tune";
  design::ArmTuningOptions tuning;  ///< joints, budget, seed, threads, stages and goals (design::tuneArm)
};

/// Adds `tune` to `app`.
CLI::App* addTuneCommand(CLI::App& app, TuneOptions& options, OptionTable& table);

/// Runs `fullarm tune`: gains.yaml (loadable by `validate`), summary.json, report.html.
/// @return 0 when every tuned joint passed the nonlinear verification stage (or, with
/// nonlinear_rounds = 0, met its linear hard goals); 4 (inconclusive) otherwise: the tuning's
/// budget ran out before gains were verified for every joint, which proves no gains infeasible.
/// @throws core::ConfigError for bad input; OutputError when the output folder cannot be written.
int runTune(const TuneOptions& options);

/// Result of the demo's tune step.
struct TuneDemoStep {
  bool pass = false;
  std::string detail;
  std::filesystem::path gains_file;  ///< the tuned gains, for the validate step
};

/// The demo step: tunes all 7 joints on the default plant with `fullarm tune`'s default budget
/// and start (so it writes the shipped dts_gains.yaml's gains), writes `tuned_gains.yaml` into
/// `out_dir` and adds its section and the `results.tune` keys to `report`.
TuneDemoStep runTuneDemoStep(const arm::ArmModel& model, const std::filesystem::path& out_dir, reports::Report& report,
                             core::Progress& progress);

}  // namespace fullarm::app
