#pragma once
/// @file
/// Gain tuning of the admittance controller, one joint at a time, in the spirit of MATLAB
/// `systune` (docs/sources.md, Control 1): minimise the worst normalised soft goal
/// subject to every normalised hard goal <= 1 over a set of plant models, the set growing by
/// the worst-case model found after each round (docs/analysis.md). NLopt: a deterministic
/// global stage (GN_ORIG_DIRECT_L, or GN_ISRES with a fixed seed) on the log-scaled
/// variables, then a local polish (LN_COBYLA); the best feasible point is tracked by the
/// tuner itself, not taken from NLopt's return value. Offline (allocates), not @rt.
///
/// Variables (log10): J_m, B_m, K_m, B_o/eps, lambda. B_o stays as given (the valve and safety
/// limit), so eps = B_o / (B_o/eps).
///
/// Hard goals, each normalised so that <= 1 is met, for every model of the set:
///   Ms / max_peak_sensitivity;  spectral radius of the closed loop (free motion and in
///   contact with the target wall) / 1;  sector: -min Re L / 1, and a loop that is unstable at
///   a gain scale of kSectorScales fails it outright (LinearChecks::sector_ok);  coupled
///   stability and damping with the validated users (coupled_stability.hpp: spectral radius and
///   the detector score of every mode, over the model set and the coupled grid of the
///   validation box); with TuningGoals::contact_hard, the same in contact with the wall (Eq. C6).
///   Passivity, 1 - min Re Z / passivity_tolerance, is computed and reported,
///   and is a hard goal only with TuningGoals::passivity_hard (docs/analysis.md).
/// Soft goals (the objective is their maximum, worst model):
///   free-motion transparency: RMS user torque to follow the reference motion / target;
///   wall accuracy: |K_rendered(wall_check_hz) / K_wall - 1| / wall_accuracy.

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fullarm/controllers/gains.hpp"
#include "fullarm/design/coupled_stability.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/uncertainty.hpp"

namespace fullarm::design {

/// Search box of the tuned variables (the tuner works on their log10).
struct TuningBounds {
  double inertia_kgm2[2] = {1e-3, 1.0};
  double damping_nms_per_rad[2] = {1e-2, 20.0};
  double stiffness_nm_per_rad[2] = {1.0, 1e3};
  double gain_v_s_per_rad[2] = {1e-3, 1e2};  ///< B_o / eps
  double lambda_per_s[2] = {1.0, 300.0};
};

/// The design specification.
struct TuningGoals {
  // Hard.
  double max_peak_sensitivity = 1.7;
  double passivity_tolerance_nms_per_rad = 0.05;  ///< Re Z >= -this counts as passive
  /// Unconditional passivity as a hard goal (false: computed and reported only; the coupled goal
  /// below is the hard one, docs/analysis.md "Coupled stability instead of unconditional passivity").
  bool passivity_hard = false;
  /// Coupled goal (coupled_stability.hpp): the closed loop with every user of the coupled grid and
  /// of the model set is stable and each of its modes is judged decaying by this detector.
  bool coupled_hard = true;
  DetectorModel detector{};
  /// Contact goal (Eq. C6, evaluateCoupledContact()): the same models held against the target
  /// wall are stable and each contact mode is judged decaying by `contact_detector`. Off by
  /// default (`fullarm tune --contact-goal`): measured on the default plant it removes the stiff
  /// users' contact oscillations of SFE's linear optimum but trades them for "too sluggish" on SFE
  /// and SAA (SAA also keeps one contact oscillation, on a plant outside the model set;
  /// docs/analysis.md, "Contact damping (Eq. C6)"). The default detector is
  /// contactDetectorModelOf() of the default ScenarioTiming; `fullarm tune` sets the scenario's.
  bool contact_hard = false;
  DetectorModel contact_detector = contactDetectorModelOf(JointScenario{});
  // Soft.
  std::vector<double> reference_hz = {0.25, 0.5, 1.0, 2.0};  ///< reference motion: sum of sines
  double reference_amplitude_rad = 0.1;                      ///< per sine
  double target_rms_torque_nm = 0.5;                         ///< free-motion goal normalisation
  double wall_stiffness_nm_per_rad = 100.0;                  ///< target wall (rendering and stability)
  double wall_damping_nms_per_rad = 0.0;
  double wall_check_hz = 1.0;
  double wall_accuracy = 0.2;  ///< relative error of the rendered stiffness that scores 1
};

enum class GlobalAlgorithm { kDirectL, kIsres };

/// Budget and determinism.
struct TunerOptions {
  GlobalAlgorithm global = GlobalAlgorithm::kDirectL;
  int global_evaluations = 300;  ///< per round
  int local_evaluations = 150;   ///< per round
  int rounds = 3;                ///< worst-case rounds (models added: rounds - 1 at most)
  int worst_case_samples = 24;   ///< random models (plus corners) searched per round
  /// Seed of the worst-case search's random models: drawVariation() with seed ^
  /// kWorstCaseSearchSalt, keyed by the joint's name (and of ISRES's generator).
  std::uint64_t seed = 1;
  int grid_points = 120;  ///< frequency grid of the goal evaluations
};

/// Goal values of one gain set over a model set (worst model), each normalised.
struct GoalValues {
  double peak_sensitivity = 0.0;  ///< Ms (raw)
  double spectral_radius = 0.0;   ///< worst of free motion and wall (free motion without a user spring: drift pole left
                                  ///< out, spectralRadiusWithoutDrift)
  double min_real_loop = 0.0;     ///< min Re L (raw)
  double min_real_impedance = 0.0;        ///< min Re Z [N m s/rad] (raw)
  double rms_user_torque_nm = 0.0;        ///< free-motion reference (raw)
  double wall_error = 0.0;                ///< relative rendered-stiffness error (raw)
  double coupled_spectral_radius = 0.0;   ///< worst over the coupled grid and the model set (drift pole left out)
  double coupled_detector_score = 0.0;    ///< worst detectorModeScore() (<= 1: judged decaying)
  double coupled_mode_hz = 0.0;           ///< frequency of the mode with that score
  double coupled_mode_decay_per_s = 0.0;  ///< and its decay rate
  double contact_spectral_radius = 0.0;   ///< worst over the model set and the coupled grid against the wall
  double contact_detector_score = 0.0;    ///< worst detectorModeScore() of a contact mode (<= 1: judged decaying)
  double contact_mode_hz = 0.0;           ///< frequency of the contact mode with that score
  double contact_mode_decay_per_s = 0.0;  ///< and its decay rate
  double hard = 0.0;                      ///< max normalised hard goal (<= 1: met)
  double soft = 0.0;                      ///< max normalised soft goal (objective)
  bool feasible() const noexcept { return hard <= 1.0; }
};

/// What tuneJoint() returns.
struct TuningResult {
  std::string joint;
  controllers::JointGains initial;
  controllers::JointGains tuned;  ///< the best feasible point found (the initial gains if none)
  bool feasible = false;
  std::string verdict;       ///< one sentence: feasible or why not
  GoalValues initial_goals;  ///< over the final model set
  GoalValues tuned_goals;    ///< of `tuned` (so of the starting gains when infeasible)
  std::vector<ModelVariation> model_set;
  /// The coupled grid of the nominal plant (coupledVariations() of the validation box).
  std::vector<PreparedJoint> coupled_models;
  /// Best feasible objective after each evaluation (NaN until the first feasible point).
  std::vector<double> history;
  /// Smallest worst normalised hard goal after each evaluation (<= 1 once a point is feasible);
  /// shows the search's progress also when nothing is feasible.
  std::vector<double> hard_history;
  int evaluations = 0;
  std::vector<std::string> nlopt_results;  ///< result code of every NLopt run, in order
};

/// Evaluates the goals of `gains` over `models` (worst case over the set); the coupled goal runs
/// over `models` and `coupled` (the coupled grid; may be empty).
[[nodiscard]] GoalValues evaluateGoals(const std::vector<PreparedJoint>& models, const controllers::JointGains& gains,
                                       const TuningGoals& goals, const std::vector<PreparedJoint>& coupled = {});

/// The worst normalised hard goal of `values` and its name ("peak sensitivity Ms", "spectral
/// radius", "sector condition Re L > -1", "coupled stability and damping over the validated users",
/// and "passivity Re Z >= 0" when TuningGoals::passivity_hard); met when the value is <= 1.
[[nodiscard]] std::pair<double, std::string> worstHardGoal(const GoalValues& values, const TuningGoals& goals);

/// Tunes one joint. `nominal` carries the joint and its load (with the user's arm), `q_rad`
/// the operating posture of the joint, `initial` the starting gains (B_o, filters and the
/// non-tuned fields are kept). Deterministic for given inputs and options.
/// @throws core::ConfigError for invalid initial gains; std::invalid_argument for bad options.
[[nodiscard]] TuningResult tuneJoint(const JointPlantModel& nominal, double q_rad,
                                     const controllers::JointGains& initial, const LoopSetup& setup,
                                     const TuningGoals& goals, const TuningBounds& bounds,
                                     const UncertaintyRanges& ranges, const TunerOptions& options);

}  // namespace fullarm::design
