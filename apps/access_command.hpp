#pragma once
// `fullarm access`: can the arm reach a scene's target, in three modes (free, contact allowed,
// hand only), with the verdicts, clearances and contacts; how hard the person can push there, with
// and without bracing, and the brace posture; and the report.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "cli_options.hpp"
#include "fullarm/accessibility/brace_search.hpp"
#include "fullarm/accessibility/reach.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// Options of `fullarm access`.
struct AccessOptions {
  std::string scene;                     ///< scene YAML with a `targets:` list (required)
  std::string target;                    ///< target name (default: the scene's first)
  std::string arm_config;                ///< arm model YAML (default: dts_master.yaml)
  std::string out_dir;                   ///< optional: summary.json and report.html
  std::int64_t seed = 1;                 ///< the planner's seed
  std::int64_t iterations = 20000;       ///< the planner's budget per mode
  std::string planner = "rrt-connect";   ///< rrt-connect | sbl
  double max_link_force_n = 40.0;        ///< contact-allowed: largest rendered force per link [N]
  double max_skin_depth_m = 0.008;       ///< contact-allowed: largest depth into the haptic skin [m]
  double clearance_m = 0.01;             ///< free and hand-only: clearance margin [m]
  std::optional<double> force_n;         ///< the push the task needs [N]; unset: no requirement
  std::string human_config;              ///< the person's arm YAML (default: config/human_arm.yaml)
  std::int64_t brace_evaluations = 120;  ///< the brace-posture search's budget
  /// Population: the number of technicians (unset: the nominal arm alone)
  std::optional<std::int64_t> population;
  double mix = 0.5;                       ///< population: the share of women in [0, 1]
  int threads = 0;                        ///< population: worker threads (0: one per core; 1 per MPI rank)
  std::string shard;                      ///< population: `i/N`, this run's shard
  std::int64_t repair_iterations = 2000;  ///< population: planner budget of each re-planned stretch
  core::Progress* progress = nullptr;     ///< population: progress lines (null: none)
};

/// Options of `fullarm access merge`.
struct AccessMergeOptions {
  std::string out_dir;              ///< the merged population's folder (required)
  std::vector<std::string> shards;  ///< the shards' technicians.sweep files
};

/// The reach options the access options give (limits, planner, budget, seed).
[[nodiscard]] accessibility::ReachOptions accessReachOptions(const AccessOptions& options);

/// The brace-search options the access options give (budget, seed, contact limits).
[[nodiscard]] accessibility::BraceSearchOptions accessBraceOptions(const AccessOptions& options);

/// Adds `access` to `app`, and its `merge` subcommand (the population's shards) with
/// `merge_options`; `merge` receives the merge subcommand.
CLI::App* addAccessCommand(CLI::App& app, AccessOptions& options, AccessMergeOptions& merge_options, CLI::App*& merge,
                           OptionTable& table);

/// Runs `fullarm access`: prints progress on stderr, the three verdicts and, when contact-allowed
/// reach finds a path, the push along the target's push direction at the reached grasp and at the
/// brace posture (with and without bracing) on stdout; with --out also summary.json and
/// report.html.
/// A population (--population) is runAccessPopulation's (access_population.hpp).
/// @return 0 when contact-allowed reach (the arm feeling its way in with full-arm haptics) says
///   reachable and, with --force, the best push reaches the force; 1 when the target is proven
///   unreachable or the person is too weak; 4 when the reach budget ran out.
/// @throws core::ConfigError / haptics::MeshError / std::invalid_argument for bad input (exit 2).
int runAccess(const AccessOptions& options);

/// Result of the demo's valve-study step.
struct AccessDemoStep {
  bool pass = false;
  std::string detail;
};

/// The demo step: the five study environments (scenes/accessibility/env1..5.yaml) in the three
/// modes; passes when each gives the verdicts it is designed for (2 unreachable with a hand-only
/// false positive, 3 free, 1/4/5 contact only). Adds a section with the verdicts to `report`.
AccessDemoStep runAccessDemoStep(const arm::ArmModel& model, reports::Report& report);

}  // namespace fullarm::app
