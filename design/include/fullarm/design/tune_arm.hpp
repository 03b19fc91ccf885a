#pragma once
/// @file
/// The arm-level tuning pipeline behind `fullarm tune` (docs/analysis.md): for each joint of a
/// gains file, the linear stage (tuner.hpp: NLopt on the linear goals over a growing model set),
/// then the nonlinear verification stage (nonlinear_stage.hpp) on `validate`'s closed-loop
/// harness, and the contact goal (Eq. C6) of the written gains; the joints run as jobs of one
/// core::JobPool whose idle workers help the running nonlinear stages with their simulations
/// (docs/analysis.md, "Scheduling of tune"). Deterministic: the result depends neither on the
/// thread count nor on which other joints are tuned. Offline (allocates, starts threads), not @rt.

#include <cstdint>
#include <string>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/design/coupled_stability.hpp"
#include "fullarm/design/joint_linearization.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/nonlinear_stage.hpp"
#include "fullarm/design/tuner.hpp"
#include "fullarm/design/validation.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::design {

/// Budget and switches of tuneArm() (the defaults are `fullarm tune`'s).
struct ArmTuningOptions {
  std::vector<std::string> joints;  ///< short or model names; empty = every joint of the gains file
  int global_evaluations = 300;     ///< TunerOptions::global_evaluations
  int local_evaluations = 150;      ///< TunerOptions::local_evaluations
  int rounds = 3;                   ///< TunerOptions::rounds
  std::uint64_t seed = 1;           ///< the linear stage's worst-case search and the nonlinear stage's samples
  int threads = 2;                  ///< workers of the job pool, the caller included (>= 1)
  int nonlinear_rounds = 3;         ///< rounds of the nonlinear verification stage (0: linear stage only)
  /// The coupled goal's V0 per mode from the free move through the closed loop (Eq. C5) or, when
  /// false, the move's peak speed (Eq. C3, a bound; docs/analysis.md, "Conservatism").
  bool modal_amplitude = true;
  /// The contact goal (Eq. C6) as a hard goal of the linear stage; it is computed for the written
  /// gains either way (ArmTuningResult::contact).
  bool contact_goal = false;
  /// Reports each joint's stages as they end (a step per stage and joint); null: silent. Not owned.
  core::Progress* progress = nullptr;
};

/// What tuneArm() returns; the vectors are indexed like ArmTuningOptions::joints (or the gains
/// file's joints when that is empty).
struct ArmTuningResult {
  controllers::GainsConfig tuned;            ///< the whole gains file with the tuned joints replaced (no source)
  std::vector<TuningResult> results;         ///< the linear stage of each tuned joint
  std::vector<PreparedJoint> nominal;        ///< the nominal linear model of each tuned joint
  std::vector<NonlinearStageResult> stages;  ///< the nonlinear stage of each joint (empty when off)
  /// The contact goal (Eq. C6) of each joint's written gains on the linear stage's model set and
  /// coupled grid, whether or not it was a hard goal.
  std::vector<CoupledGoal> contact;
  double wall_s = 0.0;  ///< wall time of the tuning [s]
  /// Every tuned joint passed: verified by the nonlinear stage, or, without it, feasible in the
  /// linear stage.
  bool pass = false;
};

/// The joint model the tuner designs for: joint `name`'s hydraulics from `plant_config`, its load
/// at the model's default posture (without the plant file's user arm), and the validation file's
/// nominal user in joint space (inertia, stiffness, damping), as `fullarm validate` simulates it.
/// @throws core::ConfigError for a joint missing from the plant file.
[[nodiscard]] JointPlantModel tunerJointModel(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                              const ValidationConfig& validation, const std::string& name);

/// Tunes the joints `options.joints` of `start` (the starting gains: B_o, filters and the other
/// non-tuned fields are kept) against `validation`'s user, wall and uncertainty ranges on the
/// plant `plant_config` of `model`. Each joint: the linear stage from `start` at the default
/// posture (the validation wall as the target wall, validate's detector for the coupled and
/// contact goals), then, with options.nonlinear_rounds > 0, the nonlinear stage from the better of
/// the linear optimum and the start; the written gains are the nonlinear stage's (the linear
/// stage's without it).
/// @throws core::ConfigError for a gains file that is not for the admittance controller or a
///         joint it lacks; std::invalid_argument for bad options.
[[nodiscard]] ArmTuningResult tuneArm(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                      const controllers::GainsConfig& start, const ValidationConfig& validation,
                                      const ArmTuningOptions& options);

}  // namespace fullarm::design
