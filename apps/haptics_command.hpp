#pragma once
// `fullarm haptics query`: minima, contact forces and joint torques of one arm configuration in
// a scene.

#include <CLI/CLI.hpp>
#include <string>

namespace fullarm::app {

/// Options of `fullarm haptics query`.
struct HapticsQueryOptions {
  std::string scene;              ///< scene YAML (required)
  std::string q_text;             ///< joint angles [rad], "q1,...,q7" (required)
  std::string out_dir;            ///< optional: write summary.json and report.html here
  std::string mode = "full-arm";  ///< full-arm | hand-only (overrides the haptics YAML)
  std::string search = "snch";    ///< snch | bullet
  std::string arm_config;         ///< arm model YAML (default: dts_master.yaml)
  std::string haptics_config;     ///< haptics YAML (default: config/haptics.yaml)
};

/// Adds `haptics` with its `query` subcommand to `app`; returns the `query` subcommand.
CLI::App* addHapticsCommand(CLI::App& app, HapticsQueryOptions& options);

/// Runs `fullarm haptics query`: prints the minima, the contact forces, the per-link contact
/// records and the joint torques; with --out also summary.json and report.html.
/// @return 0 (a query has no failing verdict), 1 if the contact computation flagged a fault.
/// @throws arm::ConfigError / haptics::MeshError / std::runtime_error for bad input (exit 2).
int runHapticsQuery(const HapticsQueryOptions& options);

}  // namespace fullarm::app
