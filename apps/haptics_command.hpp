#pragma once
// `fullarm haptics query`: minima, contact forces and joint torques of one arm configuration in
// a scene.

#include <CLI/CLI.hpp>
#include <filesystem>
#include <string>

#include "cli_options.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/reports/report.hpp"

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
CLI::App* addHapticsCommand(CLI::App& app, HapticsQueryOptions& options, OptionTable& table);

/// Runs `fullarm haptics query`: prints the minima, the contact forces, the per-link contact
/// records and the joint torques; with --out also summary.json and report.html.
/// @return 0 (a query has no failing verdict), 1 if the contact computation flagged a fault.
/// @throws core::ConfigError / haptics::MeshError / std::runtime_error for bad input (exit 2).
int runHapticsQuery(const HapticsQueryOptions& options);

/// Result of the demo's haptics step.
struct HapticsDemoStep {
  bool pass = false;
  std::string detail;
};

/// The demo step: loads the shipped scene `valve_wall.yaml` (core::defaultScenePath), poses
/// `model` at the scene's `reach_valve` posture, runs the SNCH global search once and renders the
/// minima in full-arm and in hand-only mode with the default haptics parameters; prints both,
/// adds a section with the two modes side by side (minima and forces, joint torques, per-link
/// contact records) and the `results.haptics_demo` keys to `report`.
/// Passes when neither mode flags a contact fault, the search finds at least one minimum and
/// every joint torque is finite. `out_dir` is unused (the step writes no file of its own) and
/// kept for the runXDemoStep signature.
/// @throws core::ConfigError if the scene, its meshes or the haptics parameters are invalid.
HapticsDemoStep runHapticsDemoStep(const arm::ArmModel& model, const std::filesystem::path& out_dir,
                                   reports::Report& report);

}  // namespace fullarm::app
