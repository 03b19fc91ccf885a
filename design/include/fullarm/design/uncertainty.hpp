#pragma once
/// @file
/// The uncertainty box of the plant and the user that `fullarm validate` checks and `fullarm
/// tune` designs against: its ranges, one draw of it (a model variation), the one seeded sampler,
/// and the one function that applies a variation to a joint (applyVariation), with the linear
/// model and the closed-loop scenario built on it. validation.hpp, tuner.hpp, coupled_stability.hpp
/// and nonlinear_stage.hpp all use these. Offline (allocates), not @rt, except where marked.

#include <cstdint>

#include "fullarm/design/closed_loop.hpp"
#include "fullarm/design/joint_linearization.hpp"
#include "fullarm/design/linear_analysis.hpp"

namespace fullarm::design {

/// A closed interval sampled uniformly.
struct UniformRange {
  double min = 1.0;
  double max = 1.0;
};

/// The uncertainty of one Monte-Carlo sample's plant and user, as factors on the nominal
/// values (scales) or absolute values.
struct UncertaintyRanges {
  UniformRange bulk_modulus_scale{0.6, 1.4};          ///< oil bulk modulus
  UniformRange valve_gain_scale{0.8, 1.2};            ///< valve flow gain (rated flow)
  UniformRange friction_scale{0.5, 2.0};              ///< Coulomb, static and viscous friction together
  UniformRange inertia_scale{0.8, 1.3};               ///< link + user inertia about the joint
  UniformRange user_stiffness_nm_per_rad{0.0, 75.0};  ///< K_h (0-3x Viviani's elbow)
  UniformRange user_damping_nms_per_rad{0.0, 25.0};   ///< B_h (0-3x Viviani's elbow)
  int delay_min_samples = 1;                          ///< computation delay, uniform integer in [min, max]
  int delay_max_samples = 3;
};

/// One point of the uncertainty box: a Monte-Carlo run of `validate`, a member of the tuner's
/// model set, a sample of its nonlinear stage or a node of the coupled grid.
struct ModelVariation {
  int index = 0;  ///< which draw (or corner) it is; the run's sensor-noise stream
  double bulk_modulus_scale = 1.0;
  double valve_gain_scale = 1.0;
  double friction_scale = 1.0;
  double inertia_scale = 1.0;
  double user_stiffness_nm_per_rad = 0.0;
  double user_damping_nms_per_rad = 0.0;
  int delay_samples = 1;
};

/// The one sampler of the box: draws sample `index` of joint `joint_slot` from its own
/// counter-based stream (core::RandomStream: SplitMix64 of seed, joint and index), uniform in
/// every range, the delay uniform over its integers: the same sample whatever order or thread
/// draws it. Every consumer keys its joint by core::nameSlot() of the joint's name, so a joint's
/// draws do not depend on which other joints are in the run, and salts the seed with its own
/// constant below (validate uses the seed as given), so no consumer sees another's draws. @rt
[[nodiscard]] ModelVariation drawVariation(const UncertaintyRanges& ranges, std::uint64_t seed, int joint_slot,
                                           int index) noexcept;

/// Seed salt of the tuner's worst-case search (tuneJoint's random models). ASCII "tune-wc1".
inline constexpr std::uint64_t kWorstCaseSearchSalt = 0x74756e652d776331ULL;
/// Seed salt of the nonlinear stage's samples (stageSamples()). ASCII "tune-nl1".
inline constexpr std::uint64_t kNonlinearStageSalt = 0x74756e652d6e6c31ULL;

/// The joint model of one variation, the one place where a variation meets the joint's
/// parameters: oil bulk modulus, valve rated flow and friction (Coulomb, static, viscous) scaled;
/// the inertia about the joint, link and user alike (`load.inertia_kgm2` and
/// `load.user_inertia_kgm2`), scaled by `inertia_scale` (the actuator's own inertia, a part of the
/// hydraulics, is not); the user's spring and damper set to the variation's. Gravity is kept.
[[nodiscard]] JointPlantModel applyVariation(const JointPlantModel& nominal, const ModelVariation& v);

/// The closed-loop scenario of one variation, for the nonlinear runs of `validate` and the
/// tuner's nonlinear stage: the joint model applyVariation(scenarioPlantModel(nominal), v)
/// written back (hydraulics; the scenario's load inertia = link + user inertia, both scaled; the
/// user's inertia, stiffness and damping), the variation's delay, and its own sensor-noise stream
/// (from v.index). scenarioPlantModel() of the result is that varied joint model (up to rounding).
[[nodiscard]] JointScenario variationScenario(const JointScenario& nominal, const ModelVariation& v);

/// Builds the joint model of one variation (applyVariation) at `q_rad` with the variation's delay.
[[nodiscard]] PreparedJoint prepareVariation(const JointPlantModel& nominal, double q_rad, const LoopSetup& setup,
                                             const ModelVariation& v);

}  // namespace fullarm::design
