#pragma once
/// @file
/// Closed-loop nonlinear simulation of one DTS joint: the joint controller of
/// joint_controller.hpp driving fullarm::plant's CVODES hydraulic joint at the control rate,
/// with 1-3 samples of computation delay, a user modelled as an impedance that follows a
/// reference motion (free motion), then a virtual wall rendered by the controller, and
/// automatic oscillation / instability detection.
///
/// Scenario, times from the start (all configurable in ScenarioTiming):
///   rest -> free move (minimum-jerk reference, amplitude `free_move_rad`) -> free hold
///   -> contact move (reference to `push_rad` beyond the wall) -> contact hold.
/// The user: tau_user = K_h (q_ref - q) + B_h (qd_ref - qd) on the true joint state (the human
/// feels the real arm). The wall, on the far side of the motion, rendered from the measured
/// angle: tau_env = -d (K_w p + B_w p') for penetration p = d (q - q_wall) > 0 (unilateral: it
/// never pulls), d = direction of the motion.
///
/// Stability verdict: the solver must succeed, the joint must stay off its hard stops, the
/// controller must not fault, and neither hold may oscillate. A hold oscillates when, over its
/// last `detect_window_s`, the standard deviation of the true joint speed about its window mean
/// exceeds `oscillation_speed_radps` and is at least half that of the window before (with a
/// static reference a stable loop comes to rest or creeps slowly, and a transient decays; a limit
/// cycle or a divergence does neither). In contact the wall also must not chatter: over the last
/// window the wall must not switch on and off (a quantisation-driven limit cycle of a too-stiff
/// wall, Abbott & Okamura 2005): it chatters when contact is made and then lost inside the window
/// and the standard deviation of the wall torque exceeds half its mean magnitude (and 0.5 N m).
/// A first contact late in the window (the torque rising from zero once) is not chatter. The chatter criterion is
/// evaluated on the wall torque of the true joint state (K_w p + B_w p' on the true angle and speed), not on the
/// rendered tau_env: the rendered torque carries the sensor noise floor B_w * std of the
/// backward-difference speed of the noisy, 12-bit angle (about 0.3-0.6 N m for B_w = 1 N m s/rad
/// at 1 kHz) even when the arm rests against the wall; the user feels the arm, not that signal.

#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/controllers/joint_controller.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/joint_params.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::design {

/// A hold oscillates when its late window's speed deviation is above the threshold and at least
/// this fraction of the window before it (a decaying transient is not an oscillation).
inline constexpr double kOscillationSustainRatio = 0.5;

/// The user's arm at one joint: an impedance following a reference motion.
struct UserImpedance {
  double stiffness_nm_per_rad = 25.0;  ///< K_h (Viviani et al. 1976 elbow: ~25 N m/rad)
  double damping_nms_per_rad = 8.3;    ///< B_h (Viviani: ~8.3 N m s/rad)
  double inertia_kgm2 = 0.06;          ///< strapped to the link (forearm ~0.06 kg m^2)
};

/// A unilateral virtual wall.
struct ScenarioWall {
  bool enabled = true;
  double stiffness_nm_per_rad = 200.0;  ///< K_w
  double damping_nms_per_rad = 1.0;     ///< B_w
};

/// Durations and amplitudes of the scenario.
struct ScenarioTiming {
  double rest_s = 0.2;
  double free_move_s = 0.5;
  double free_hold_s = 1.1;
  double contact_move_s = 0.3;
  double contact_hold_s = 1.5;
  double free_move_rad = 0.3;  ///< reference travel in free space (toward `direction`)
  double wall_gap_rad = 0.05;  ///< wall this far beyond the end of the free move
  double push_rad = 0.1;       ///< reference this far beyond the wall (user pushes ~K_h push)
  /// Length of the detector's windows at the end of each hold: at least one period of the
  /// slowest closed-loop mode the Monte-Carlo produces (the user's stiffness against the device,
  /// 1.5-2 Hz), so that a decaying ring and a limit cycle can be told apart.
  double detect_window_s = 0.5;
};

/// Everything one closed-loop run needs. Built by makeJointScenario() from the configuration
/// files, then perturbed (Monte-Carlo) by the caller.
struct JointScenario {
  std::string joint_name;
  plant::JointParams joint{};  ///< hydraulics (fullarm::plant)
  plant::RigidLoad load{};     ///< link inertia about the axis (arm posture) + user inertia; gravity
  plant::SolverOptions solver{};
  std::uint64_t noise_seed = 1;
  controllers::JointGains gains{};
  controllers::ControllerKind kind = controllers::ControllerKind::kAdmittance;
  double dt_s = 1.0e-3;
  int delay_samples = 1;  ///< the command computed at step k acts during period k + delay
  /// Gravity the controller expects: fullarm::arm's g(q) of this joint, with the rest of the
  /// arm at the posture, written a cos q + b sin q (exact for one joint; coefficients from
  /// arm::computeGravityTorques). Equals the plant's load gravity unless a test perturbs it.
  double expected_gravity_cos_nm = 0.0;
  double expected_gravity_sin_nm = 0.0;
  double start_rad = 0.0;  ///< initial joint angle
  int direction = 1;       ///< +1 / -1: sense of the free motion and side of the wall
  UserImpedance user{};
  ScenarioWall wall{};
  ScenarioTiming timing{};
  double oscillation_speed_radps = 0.05;  ///< detector threshold
  /// A stable run is "too sluggish" when the wall was not reached although the user pushed, over
  /// the last contact window, with more than this multiple of the joint's breakaway (static
  /// friction) torque: the device resisted a push it should follow, so contact was not tested.
  double sluggish_push_friction_ratio = 2.0;
  /// Fault injection: from this time on the load-cell reading given to the controller is NaN
  /// (a broken sensor); negative = never.
  double inject_nan_torque_at_s = -1.0;
};

/// Builds the nominal scenario of arm joint `name` (model name or short name): plant joint
/// parameters from `plant_config`, gains and period from `gains`, inertia and gravity of the
/// link about its axis from `model` at its default posture, motion toward the farther joint
/// limit, sized to fit inside the limits.
/// @throws core::ConfigError for an unknown joint or a joint missing from a file.
[[nodiscard]] JointScenario makeJointScenario(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                              const controllers::GainsConfig& gains, std::string_view name);

/// Time series of one run (for plots), one entry per control period.
struct ClosedLoopTrace {
  std::vector<double> t_s, q_rad, q_ref_rad, qd_radps, tau_user_nm, tau_env_nm, tau_cell_nm, valve_v, po_energy_j;
};

/// Outcome and figures of merit of one run.
struct ClosedLoopResult {
  bool stable = false;  ///< solver ok, off the stops, no oscillation, no controller fault
  bool solver_ok = true;
  bool hit_stop = false;     ///< the joint reached a hard stop
  bool oscillating = false;  ///< a hold window's RMS speed exceeded the threshold
  std::uint32_t controller_faults = 0;
  double free_hold_speed_rms_radps = 0.0;     ///< std of the speed about its mean, last free-hold window
  double contact_hold_speed_rms_radps = 0.0;  ///< same, last contact-hold window
  /// Std of the speed over the window before the last free-hold window (the detector's ratio
  /// test compares the two).
  double free_hold_early_speed_rms_radps = 0.0;
  double contact_hold_early_speed_rms_radps = 0.0;  ///< same, contact hold
  double oscillation_frequency_hz = 0.0;            ///< from zero crossings of the speed in the worst window
  // Transparency in free space (free move phase).
  double free_rms_user_torque_nm = 0.0;
  double free_peak_user_torque_nm = 0.0;  ///< peak |tau_user| over the free move (onset spike)
  double onset_peak_valve_v = 0.0;        ///< peak |valve command| in the first 0.1 s of the free move
  // Wall rendering (contact hold window).
  double contact_penetration_rad = 0.0;  ///< mean penetration
  double contact_wall_torque_nm = 0.0;   ///< mean |tau_env|
  /// Std of the wall torque of the true joint state (stiffness and damping on the true angle and
  /// speed) over the last contact window: what the chatter criterion judges.
  double contact_wall_torque_deviation_nm = 0.0;
  /// Std of the rendered tau_env (measured angle, backward-difference speed) over the same
  /// window; includes the sensor noise floor B_w * std(backward-difference speed).
  double contact_rendered_wall_torque_deviation_nm = 0.0;
  /// In the last contact window the true state touched the wall and then left it again.
  bool contact_lost = false;
  double contact_user_torque_nm = 0.0;  ///< mean |tau_user| over the last contact window
  /// The wall carried at least half of the user's push over the last contact window (contact was
  /// really tested; a sluggish controller may never reach the wall).
  bool wall_reached = false;
  /// Stable, the wall not reached, and the user's mean push over the last contact window above
  /// JointScenario::sluggish_push_friction_ratio x the static friction: a failure of `validate`
  /// (the gains are too sluggish for the user's push), not an instability.
  bool sluggish = false;
  /// The push above which a run that does not reach the wall is too sluggish:
  /// JointScenario::sluggish_push_friction_ratio x the breakaway torque [N m].
  double sluggish_push_limit_nm = 0.0;
  double contact_rendered_stiffness_nm_per_rad = 0.0;  ///< mean |tau_user| / mean penetration
  double min_po_energy_j = 0.0;                        ///< lowest passivity-observer energy
  double po_dissipated_j = 0.0;
  long solver_steps = 0;
  std::string failure;  ///< short reason when not stable (or when sluggish)
  /// Passes the validation: stable and not sluggish.
  [[nodiscard]] bool acceptable() const noexcept { return stable && !sluggish; }
};

/// Runs the scenario. Allocates only for the trace (when `trace` is not null) and the delay line.
[[nodiscard]] ClosedLoopResult simulateJoint(const JointScenario& scenario, ClosedLoopTrace* trace = nullptr);

/// Minimum-jerk interpolation 10 s^3 - 15 s^4 + 6 s^5 of s = clamp(t / T, 0, 1), and its rate.
struct MinJerk {
  double position = 0.0;
  double rate_per_s = 0.0;
};
[[nodiscard]] MinJerk minimumJerk(double t_s, double duration_s) noexcept;

/// The scenario's reference angle and rate at time t.
[[nodiscard]] MinJerk scenarioReference(const JointScenario& scenario, double t_s) noexcept;

/// Angle of the wall surface.
[[nodiscard]] double wallPosition(const JointScenario& scenario) noexcept;

}  // namespace fullarm::design
