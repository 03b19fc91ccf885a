#pragma once
// `fullarm validate` and the validate step of `fullarm demo`.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>

#include "cli_options.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// Options of `fullarm validate`.
struct ValidateOptions {
  std::string arm_config;     ///< arm model YAML (default: dts_master.yaml)
  std::string plant_config;   ///< --plant (default: dts_plant.yaml)
  std::string gains_config;   ///< --gains (default: dts_gains.yaml)
  std::string ranges_config;  ///< --ranges (default: dts_validation.yaml)
  std::string out_dir = "out/validate";
  std::optional<int> samples;          ///< overrides the ranges file
  std::optional<std::int64_t> seed;    ///< overrides the ranges file
  int threads = 0;                     ///< 0: hardware concurrency
  std::string joints;                  ///< comma-separated subset (default: every joint of the gains file)
  bool paper_claim = false;            ///< also measure the paper's claim per joint
  core::Progress* progress = nullptr;  ///< where the validation reports its progress (null: silent)
};

/// Adds `validate` to `app`.
CLI::App* addValidateCommand(CLI::App& app, ValidateOptions& options, OptionTable& table);

/// Runs `fullarm validate`: per joint the linear checks, then the Monte-Carlo of nonlinear
/// closed-loop simulations; summary.json and report.html in the output folder.
/// @return 0 when every joint passes, 1 otherwise.
/// @throws core::ConfigError for bad input; OutputError when the output folder cannot be written.
int runValidate(const ValidateOptions& options);

/// Result of the demo's validate step.
struct ValidateDemoStep {
  bool pass = false;
  std::string detail;
};

/// The demo step: `validate` of `gains` on the default plant with `samples` Monte-Carlo runs
/// per joint and the paper-claim measurement on the elbow; adds its sections and the
/// `results.validate` keys to `report`.
ValidateDemoStep runValidateDemoStep(const arm::ArmModel& model, const std::filesystem::path& gains, int samples,
                                     reports::Report& report, core::Progress& progress);

}  // namespace fullarm::app
