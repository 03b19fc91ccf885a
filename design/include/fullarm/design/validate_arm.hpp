#pragma once
/// @file
/// The arm-level validation pipeline behind `fullarm validate` (docs/analysis.md, "Monte-Carlo
/// validation"): per joint of a gains file, the linear checks of scenario_analysis.hpp on the
/// validation scenario, optionally the paper-claim measurement (paper_claim.hpp), then the
/// seeded Monte-Carlo of nonlinear closed-loop runs (validation.hpp), the worst run simulated
/// again with its trace, and the joint's verdict. Results do not depend on the thread count nor on
/// which other joints are validated. Offline (allocates, starts threads), not @rt.

#include <filesystem>
#include <string>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/design/closed_loop.hpp"
#include "fullarm/design/paper_claim.hpp"
#include "fullarm/design/scenario_analysis.hpp"
#include "fullarm/design/uncertainty.hpp"
#include "fullarm/design/validation.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::design {

/// Wall dampings of the Z-width curve of every joint [N m s/rad].
inline constexpr double kValidationZWidthDampings[] = {0.0, 0.5, 1.0, 2.0, 5.0, 10.0};

/// What validateArm() does besides the linear checks and the Monte-Carlo.
struct ArmValidationOptions {
  std::vector<std::string> joints;  ///< short or model names; empty = every joint of the gains file
  int threads = 0;                  ///< worker threads (<= 0: hardware concurrency)
  bool paper_claim = false;         ///< also measure the paper's claim (measurePaperClaim)
  /// The joints whose claim is measured (short or model names); empty = every validated joint.
  std::vector<std::string> paper_claim_joints;
  /// Reports the linear checks (a step per joint) and the Monte-Carlo (a unit per run); null:
  /// silent. Not owned.
  core::Progress* progress = nullptr;
};

/// Everything validateArm() computes for one joint.
struct JointValidationResult {
  JointScenario nominal;        ///< the validation scenario (validationScenario())
  ScenarioLinearResult linear;  ///< analyzeScenario() at delays 1..delay_max_samples
  JointMonteCarlo monte_carlo;  ///< runMonteCarlo()
  bool pass = false;            ///< linear.pass and monte_carlo.pass()
  std::string verdict;          ///< "pass", or why not (the linear reason, the worst failed run)
  bool has_claim = false;       ///< `claim` was measured
  PaperClaimResult claim;
  ClosedLoopTrace worst_trace;    ///< of the most severe run, simulated again
  ClosedLoopResult worst_result;  ///< its result (equal to the Monte-Carlo's)
};

/// What validateArm() returns.
struct ArmValidationResult {
  std::vector<JointValidationResult> joints;  ///< in the order of ArmValidationOptions::joints (or the file's)
  ValidationConfig config;                    ///< the configuration validated against
  std::filesystem::path gains_source;         ///< the gains file
  int threads = 1;                            ///< worker threads used
  double wall_s = 0.0;                        ///< wall time of the whole validation [s]
  double monte_carlo_wall_s = 0.0;            ///< of the Monte-Carlo alone [s]
  /// Every joint passed (false when there is none).
  [[nodiscard]] bool pass() const noexcept;
};

/// One line naming the drawn values of a variation ("bulk modulus x0.83, valve gain x1.1, ...").
[[nodiscard]] std::string describeVariation(const ModelVariation& v);

/// Validates the joints `options.joints` of `gains` on the plant `plant_config` of `model`
/// against `config`: each joint's validation scenario (makeJointScenario() with the config's user,
/// wall and detector threshold), its linear checks (the verdict gated as config.linear says) and,
/// when asked, the paper-claim measurement, one job per joint; then config.samples Monte-Carlo
/// runs per joint; PASS needs both.
/// @throws core::ConfigError for a joint missing from a file; std::runtime_error when a trim
///         of the linear checks does not exist.
[[nodiscard]] ArmValidationResult validateArm(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                              const controllers::GainsConfig& gains, const ValidationConfig& config,
                                              const ArmValidationOptions& options);

}  // namespace fullarm::design
