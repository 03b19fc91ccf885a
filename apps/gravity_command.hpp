#pragma once
// `fullarm gravity`: the arm's gravity load fitted physically consistent, to the DTS reference's
// identified torques or to a static-holds log, written as an arm YAML.

#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

#include "cli_options.hpp"

namespace fullarm::app {

/// Options of `fullarm gravity`.
struct GravityOptions {
  std::string arm_config;  ///< --config (default: dts_master.yaml)
  std::string holds;       ///< --holds: a static-holds log to fit (default: the reference's torques)
  int postures = 400;      ///< --postures: random postures of the fit to the reference
  int seed = 1;            ///< --seed: which random postures
  std::string out_dir = "out/gravity";
};

/// Adds `gravity` to `app`.
CLI::App* addGravityCommand(CLI::App& app, GravityOptions& options, OptionTable& table);

/// Fits, prints the residual per joint, writes `arm.yaml` (the arm file with the fitted masses
/// and centres of mass) and `gravity.csv` (the per-joint table) into --out.
/// @return 0 when written
/// @throws core::ConfigError for bad input (a malformed holds log names the line); OutputError
int runGravity(const GravityOptions& options, std::ostream& out);

}  // namespace fullarm::app
