#pragma once
/// @file
/// Offline stability validation of the joint controllers (`fullarm validate`): a seeded
/// Monte-Carlo over plant and user uncertainty, each sample a nonlinear closed-loop simulation
/// (closed_loop.hpp: free motion, then a virtual wall), run on a thread pool with results that
/// do not depend on the number of threads. Ranges come from config/dts_validation.yaml
/// (schema: docs/analysis.md).

#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/core/progress.hpp"
#include "fullarm/design/closed_loop.hpp"
#include "fullarm/design/scenario_analysis.hpp"
#include "fullarm/design/uncertainty.hpp"

namespace fullarm::design {

/// A validation file.
struct ValidationConfig {
  std::filesystem::path source;
  int samples = 300;       ///< Monte-Carlo runs per joint (>= 1; 300 bounds a failure rate of 1 % at 95 % confidence)
  std::uint64_t seed = 1;  ///< the runs depend only on (seed, joint, run index)
  UserImpedance user{};    ///< nominal user (inertia used for every sample)
  ScenarioWall wall{};     ///< the wall rendered in every run
  double oscillation_speed_radps = 0.05;
  UncertaintyRanges ranges{};
  LinearRequirements linear{};  ///< which linear results gate the verdict
};

/// Loads and validates a validation file (strict: missing and unknown keys are errors; every
/// range needs min <= max within physical bounds).
/// @throws core::ConfigError naming the file, line, key path and what was expected.
[[nodiscard]] ValidationConfig loadValidationConfig(const std::filesystem::path& file);
/// Parses validation YAML text; `source` names it in errors. @throws core::ConfigError
[[nodiscard]] ValidationConfig parseValidationConfig(std::string_view yaml_text, const std::filesystem::path& source);
/// $FULLARM_CONFIG_DIR/dts_validation.yaml if set, else the source-tree or installed config folder.
[[nodiscard]] std::filesystem::path defaultValidationConfigPath();

/// One Monte-Carlo run.
struct MonteCarloRun {
  ModelVariation sample;
  ClosedLoopResult result;
  /// How close to failing: 1 + |result| badness for a failed (unstable or sluggish) run; otherwise the largest hold
  /// speed deviation over the detector threshold (in [0, 1]). The worst case maximises it.
  double severity = 0.0;
};

/// The Monte-Carlo of one joint.
struct JointMonteCarlo {
  std::string joint_name;
  std::vector<MonteCarloRun> runs;
  int failures = 0;          ///< runs not acceptable(): unstable, or too sluggish
  int sluggish = 0;          ///< of the failures: stable but too sluggish to reach the wall
  int wall_not_reached = 0;  ///< passed runs in which the wall never carried the user's push (a light push)
  int worst = -1;            ///< index in runs of the largest severity
  [[nodiscard]] bool pass() const noexcept { return failures == 0 && !runs.empty(); }
};

/// Severity of a result (see MonteCarloRun::severity).
[[nodiscard]] double runSeverity(const ClosedLoopResult& result, double oscillation_speed_radps) noexcept;

/// The nominal scenario as the validation runs it: the config's user (its inertia replacing the
/// scenario's user inertia in the load), wall and detector threshold.
[[nodiscard]] JointScenario validationScenario(const JointScenario& nominal, const ValidationConfig& config);

/// Runs `config.samples` simulations of every nominal scenario (its user, wall and detector
/// replaced by the config's) on `threads` worker threads (<= 0: hardware concurrency).
/// Results are identical for any thread count. Reports each finished run as a unit of
/// `progress` (a task "validate: Monte-Carlo" of samples x joints runs) unless it is null.
[[nodiscard]] std::vector<JointMonteCarlo> runMonteCarlo(const std::vector<JointScenario>& nominal,
                                                         const ValidationConfig& config, int threads,
                                                         core::Progress* progress = nullptr);

/// Runs `jobs` calls of `job(i)` for i in [0, jobs) on `threads` worker threads (<= 0: hardware
/// concurrency), each index exactly once; rethrows the first exception after all threads end.
void parallelFor(int jobs, int threads, const std::function<void(int)>& job);

}  // namespace fullarm::design
