#pragma once
/// @file
/// The tuner's nonlinear verification stage (docs/analysis.md, "Tuned vs validated"). The linear
/// goals of tuner.hpp cannot see what makes `fullarm validate` fail on the nonlinear plant:
/// Stribeck friction (stick-slip at the wall), the valve's underlap, sensor noise and 12-bit
/// quantisation, and a device too sluggish to reach the wall under the user's push. This stage
/// scores a candidate on a small seeded Monte-Carlo of the same closed-loop harness and
/// uncertainty ranges that `validate` uses (but its own sample stream, so the tuner does not
/// see validate's draws), and refines the candidate with a deterministic compass search on
/// log10 B_m and log10 B_o/eps (the two gains that, measured, trade contact oscillation against
/// sluggishness; J_m, K_m, lambda keep the linear stage's values). In the spirit of systune's
/// worst-case model addition, each round ends with a fresh check batch on the incumbent; its
/// failed samples join the sample set and the search goes on. Offline (allocates), not @rt.
///
/// Score of a candidate over a sample set (lower is better):
///   cost = failures + (1 - 1 / (1 + mean RMS user torque over the free move [N m]))
/// so a failed run always outweighs any transparency difference; a candidate whose linear check
/// of `validate` fails (closed loop unstable at some delay, free or against the wall) is rejected.

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "fullarm/controllers/closed_loop.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/controllers/scenario_analysis.hpp"
#include "fullarm/controllers/validation.hpp"

namespace fullarm::controllers {

/// Budget and determinism of the stage.
struct NonlinearStageOptions {
  int samples = 16;  ///< initial sample set (runs per candidate evaluation)
  /// Fresh runs on the incumbent at the end of each round (half of validate's 300, a budget
  /// choice for the 120 s tuning target: a failure rate of 1 % escapes one batch with
  /// probability 0.22). The batch stops early once max_added_per_round runs have failed.
  int check_samples = 150;
  int rounds = 3;             ///< search rounds (each followed by a check batch)
  int max_evaluations = 14;   ///< candidate evaluations per round's compass search
  double step_decades = 0.3;  ///< initial compass step on log10 B_m and log10 B_o/eps
  double min_step_decades = 0.04;
  int max_added_per_round = 4;  ///< failed check samples added to the set per round (worst first)
  std::uint64_t seed = 1;
  double min_damping_nms_per_rad = 0.05;  ///< search box of B_m
  double max_damping_nms_per_rad = 60.0;
  double min_gain_v_s_per_rad = 1e-3;  ///< search box of B_o/eps
  double max_gain_v_s_per_rad = 1.0;
};

/// The score of one candidate over a sample set.
struct NonlinearScore {
  bool linear_ok = false;                ///< validate's linear check passes
  int failures = 0;                      ///< runs not acceptable() (unstable or too sluggish)
  int runs = 0;                          ///< runs made (fewer than the set when stopped at the failure cap)
  double mean_rms_user_torque_nm = 0.0;  ///< over the free move, mean over the runs
  double cost = 0.0;                     ///< +inf when !linear_ok
  int worst = -1;                        ///< index in the sample set of the most severe run
  std::string worst_failure;
};

/// What refineNonlinear() returns.
struct NonlinearStageResult {
  JointGains gains;                   ///< the refined gains (linear optimum or start when already best)
  NonlinearScore linear_optimum;      ///< score of the linear stage's gains on the initial set
  NonlinearScore start;               ///< score of the starting gains on the initial set
  NonlinearScore final_score;         ///< score of `gains` on the final set
  std::vector<int> check_failures;    ///< failures of each round's check batch (capped: early stop)
  std::vector<MonteCarloSample> set;  ///< the final sample set (initial + added worst cases)
  std::vector<double> history;        ///< best cost after each evaluation
  int evaluations = 0;                ///< candidate evaluations (each = set.size() simulations)
  int simulations = 0;                ///< closed-loop runs in total
  bool verified = false;              ///< the last check batch and the final set had no failure
  std::string verdict;                ///< one sentence
};

/// Scores `gains` on `scenario` (a validation scenario: validationScenario()) over `set`.
/// `max_delay` is the largest computation delay of the linear check. The runs stop once more
/// than `failure_cap` have failed (`runs` then counts the runs made; the candidate cannot beat an
/// incumbent with `failure_cap` failures).
[[nodiscard]] NonlinearScore scoreNonlinear(const JointScenario& scenario, const JointGains& gains,
                                            const std::vector<MonteCarloSample>& set, const LinearRequirements& req,
                                            int max_delay, int failure_cap = std::numeric_limits<int>::max());

/// Draws `count` samples of the stage's own stream (seed salted, so not validate's draws) for
/// joint `joint_name`, indices [first, first + count).
[[nodiscard]] std::vector<MonteCarloSample> stageSamples(const UncertaintyRanges& ranges, std::uint64_t seed,
                                                         const std::string& joint_name, int first, int count);

/// The stage: starts from the better of `linear_optimum` and `start` (by cost on the initial
/// set), compass search, check batches and worst-case additions as described above.
/// Deterministic for given inputs. @throws std::invalid_argument for bad options.
[[nodiscard]] NonlinearStageResult refineNonlinear(const JointScenario& scenario, const JointGains& linear_optimum,
                                                   const JointGains& start, const UncertaintyRanges& ranges,
                                                   const LinearRequirements& req, const NonlinearStageOptions& options);

}  // namespace fullarm::controllers
