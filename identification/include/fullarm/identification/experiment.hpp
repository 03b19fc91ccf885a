#pragma once
/// @file
/// A closed-loop identification experiment on one joint through an I/O device (the simulated
/// DTS, the fake DAQ or the real arm).
///
/// The DTS joints cannot run open loop near their stops, so every joint of the device is held
/// by a low-gain proportional position hold u_j = K_j (q_hold_j - q_j) about the angle it had
/// when the experiment started (the driven joint, optionally, about a hold angle it first moves
/// to), and the excitation r is added to the driven joint's valve command:
/// u = K (q_hold - q) + r. The device first ramps its outputs in (its safety policy); the
/// excitation starts after a settling time. The run stops early, with the outputs at their
/// safe value (valve null), when the driven joint comes within a margin of its limits, its load
/// cell reads out of range, a held joint drifts too far from its hold, or the device reports a
/// fault. A driven joint that starts within the margin of a limit, with no hold angle to move
/// it away, is refused before anything moves (ExperimentRefused).
///
/// The log has one row per control period of the excitation: `time_s` (the reading's device
/// time, or the control time: ExperimentOptions::log_control_time), `excitation_v`, `command_v`
/// (what the device put out after its clamp, held over the next period), `q_rad` and
/// `tau_measured_nm` (the driven joint's reading), then, where the device reads the driven
/// joint's chamber pressures (hil::JointSample::pressure_mask), `pressure_a_pa` and
/// `pressure_b_pa`, then, when the device's joints are named
/// (ExperimentOptions::joint_names), `held_<joint>_rad` for every held joint: the posture the
/// driven joint moved in, which sets its link inertia and gravity load (heldAngles reads it back).

#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "fullarm/hil/io_device.hpp"
#include "fullarm/identification/excitation.hpp"
#include "fullarm/identification/signal_csv.hpp"

namespace fullarm::identification {

/// An experiment the arm's posture does not allow, refused before the device was activated
/// (nothing moved): the driven joint starts within the margin of one of its limits and no hold
/// angle was given to move it away first. The message names the joint, its angle and the range
/// it must be in.
class ExperimentRefused : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Settings of one experiment.
struct ExperimentOptions {
  int joint = 0;                      ///< the driven joint (device order)
  double hold_gain_v_per_rad = 10.0;  ///< K of the driven joint's position hold
  double held_gain_v_per_rad = 30.0;  ///< K of the other joints' holds
  double settle_s = 1.0;              ///< hold without excitation first (covers the device's ramp-in)
  double min_rad = -1.0;              ///< the driven joint's lower limit
  double max_rad = 1.0;               ///< the driven joint's upper limit
  double limit_margin_rad = 0.05;     ///< stop when the driven joint comes this close to a limit
  double held_drift_limit_rad = 0.1;  ///< stop when a held joint leaves its hold by more than this
  /// The driven joint's hold angle (empty: the angle it starts at). It must lie inside the limits
  /// less the margin. The hold target first moves from the start to it along a cosine blend (zero
  /// speed at both ends) over at least move_s, longer when it would average more than
  /// move_speed_radps, the other joints holding where they started; then the settling time and
  /// the excitation. The start may lie within the margin (an arm resting at a stop): during the
  /// move the joint must not come closer to the limit than it started, less half the margin for
  /// the readings' noise and the sag onto the stop while the hold takes the load (a start beyond
  /// the limits is a device error), nor leave its moving target by more than move_max_error_rad. Under the proportional
  /// hold the joint settles off its target by the hold's droop (the command that carries its load, over K): a hold
  /// angle needs that much room inside the margin.
  std::optional<double> hold_rad;
  double move_s = 1.0;              ///< shortest move to the hold angle
  double move_speed_radps = 0.2;    ///< the move's largest mean speed
  double move_max_error_rad = 0.1;  ///< stop when the joint leaves its moving target by more than this
  /// Called before every read of the run (empty: none). A simulated device advances one period
  /// per read; a real board answers at once, so the caller paces its reads here (a wait for the
  /// next period on the real-time clock). Returning false stops the run before that read (the
  /// pacing missed its period: readings that no longer come a period apart would corrupt the
  /// log's time base), with the stop reason saying so.
  std::function<bool()> before_read;
  /// true: the log's `time_s` is the control time, the first logged reading's device time plus
  /// the periods since; false: each reading's device time. A board's readings carry the wall
  /// clock (with the wake-up jitter of a real board, and on the fake DAQ the wall clock of a
  /// simulation that runs faster than real time), while the fit needs a uniform time step.
  bool log_control_time = false;
  /// The device joints' names, in device order (empty: the held joints' angles are not logged).
  /// Each held joint's angle is logged as `held_<name>_rad`.
  std::vector<std::string> joint_names;
};

/// Outcome of one experiment.
struct ExperimentResult {
  SignalTable log;               ///< kExperimentColumns, one row per excitation sample run
  std::vector<double> hold_rad;  ///< the hold angle of every device joint (the driven joint's after its move)
  bool completed = false;        ///< the whole excitation ran
  std::string stop_reason;       ///< why it stopped early (empty when completed)
};

/// A held joint's angle over an experiment log.
struct HeldAngle {
  std::string joint;    ///< the name in its column `held_<joint>_rad`
  double mean_rad = 0;  ///< its mean over the log's rows
};

/// The held joints' angles of an experiment log: every column named `held_<joint>_rad`, in column
/// order, each averaged over the rows (NaN for a log without rows). Empty for a log without them
/// (a joint run alone, or a log written before they were logged).
[[nodiscard]] std::vector<HeldAngle> heldAngles(const SignalTable& log);

/// The column of a held joint's angle: `held_<joint>_rad`.
[[nodiscard]] std::string heldAngleColumn(const std::string& joint);

/// True when `name` can name a joint in a log: not empty, and none of the characters a CSV
/// field or header would split on (comma, white space, quote).
[[nodiscard]] bool isLoggableJointName(const std::string& name) noexcept;

/// Runs the experiment: configures the device if needed, activates it, moves the driven joint to
/// `options.hold_rad` if given, holds for `options.settle_s`, plays `excitation` on the driven
/// joint, then deactivates the device (safe outputs) whatever happened.
/// @throws std::invalid_argument for a joint outside the device, an excitation whose period
///   differs from the device's, limits that leave no room, a settling time that is negative or not
///   finite, a hold angle or move settings that are
///   not finite or outside the limits less the margin, or joint names that are not one non-empty
///   name per device joint
/// @throws ExperimentRefused when the driven joint starts within the margin of a limit and no hold
///   angle was given
/// @throws hil::DeviceError when the device cannot be read before the run, or the driven joint's
///   first reading is out of range or beyond its limits (a sensor, calibration or limits that are
///   wrong)
[[nodiscard]] ExperimentResult runExperiment(hil::IoDevice& device, const SampledSignal& excitation,
                                             const ExperimentOptions& options);

/// Runs several experiments in one activation of the device, as runExperiment runs one: the move
/// to the hold angle if given, then for each excitation in turn the settling time and the
/// excitation, each logged on its own (its control time starting at its first reading). The holds
/// continue from one experiment to the next: the driven joint is held at the same angle
/// throughout, with no deactivation, ramp-in or new move between them. A joint that a gravity load
/// drifted off its hold over one experiment is still pulled back to the hold angle for the next,
/// where a new run would take up its hold where the joint drifted to, after letting it sag through
/// the ramp-in (docs/identification.md). A stop ends the experiment under way (its stop reason, its log so far); the
/// ones after it do not run (stop reason "not run: " and the reason, no rows).
/// @throws as runExperiment, and std::invalid_argument for no excitation
[[nodiscard]] std::vector<ExperimentResult> runExperiments(hil::IoDevice& device,
                                                           const std::vector<SampledSignal>& excitations,
                                                           const ExperimentOptions& options);

}  // namespace fullarm::identification
