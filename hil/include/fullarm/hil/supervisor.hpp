#pragma once
/// @file
/// The safety supervisor of the haptic tick (docs/hil.md, "Safety"): every check on the inputs,
/// the start-up guard, the E-stop latch, the fade of the contact forces when the global minima
/// go stale, and the output limits. Model/Data split; every step function is @rt.
///
/// States: kStartup (no force: the valves stay at null until the sensors have been valid for
/// startup_valid_s and the arm is inside its joint limits), kRunning, kTripped (latched: the
/// valves at null, which locks the joints hydraulically, until an explicit reset command; then
/// kStartup again). Each trip and each change of the contact fade is recorded as an event with
/// its cause, tick and time.

#include <array>
#include <cstdint>
#include <limits>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/joint_selection.hpp"
#include "fullarm/core/rt_status.hpp"
#include "fullarm/hil/io_device.hpp"

namespace fullarm::hil {

/// Supervisor parameters (the `supervisor` section of config/hil.yaml).
struct SupervisorParams {
  /// Trip when a joint reads beyond its range by more than this [rad] (the arm cannot get
  /// there: a sensor or mechanical fault).
  double position_margin_rad = 0.02;
  /// Trip when the filtered joint speed exceeds this factor x the joint's velocity limit.
  double velocity_limit_factor = 1.5;
  /// Cutoff of the low-pass on the differenced joint angle for the velocity check [Hz].
  double velocity_filter_hz = 20.0;
  /// Trip when two successive readings differ by more than this rate [rad/s]: no arm moves so
  /// fast, so the reading is implausible.
  double max_plausible_rate_radps = 20.0;
  /// Trip when a load cell reads beyond this factor x the joint's torque limit.
  double torque_limit_factor = 1.2;
  /// Trip when a valve command exceeds the joint's valve limit by more than this [V].
  double valve_limit_tolerance_v = 1e-9;
  /// Start-up guard: sensors valid and the arm inside its limits for this long before any
  /// force [s].
  double startup_valid_s = 0.2;
  /// Global minima are stale after this many global periods without a new set.
  int stale_global_periods = 4;
  /// The global search's period [s] (100 Hz in the paper).
  double global_period_s = 0.01;
  /// Stale minima: the contact forces fade to zero over this time [s] ...
  double fade_s = 0.15;
  /// ... and no joint's contact torque changes faster than this while fading or recovering
  /// [N m/s].
  double max_fade_rate_nm_per_s = 100.0;
  /// E-stop when the heartbeat counter has not changed for this long [s].
  double heartbeat_timeout_s = 0.25;
  /// Communication lost when a peer node's heartbeat (the global node's, in a real-time run
  /// over LCM) has not come for this long [s]; longer than the stale-minima fade, so the contact
  /// forces have faded at their rate when the valves go to null.
  double peer_heartbeat_timeout_s = 0.5;
};

/// Why the supervisor acted.
enum class SupervisorCause : std::uint8_t {
  kNone = 0,
  kSensorNonFinite,    ///< a reading is NaN or infinite
  kSensorOutOfRange,   ///< a converter reported a reading at the end of its range
  kSensorRate,         ///< two successive readings imply an impossible speed
  kPositionLimit,      ///< a joint beyond its range
  kVelocityLimit,      ///< a joint faster than its limit
  kTorqueLimit,        ///< a load cell beyond its limit
  kValveCommandLimit,  ///< a valve command beyond its limit
  kEstopCommand,       ///< E-stop by command
  kEstopSignal,        ///< E-stop by a signal (SIGINT, SIGTERM)
  kHeartbeatLost,      ///< the heartbeat stopped
  kOverrun,            ///< too many consecutive loop overruns
  kDeviceFault,        ///< the I/O device failed
  kControllerFault,    ///< the controller faulted (non-finite input or state)
  kContactFault,       ///< the contact computation faulted
  kStartupComplete,    ///< (event) the start-up guard released the forces
  kMinimaStale,        ///< (event) the global minima went stale: the contact forces fade
  kMinimaFresh,        ///< (event) a new minima set arrived: the contact forces come back
  kReset,              ///< (event) reset by command
  kCommunicationLost,  ///< the link to a remote I/O node is lost (the device's kFaultLinkLost)
  kPeerHeartbeatLost,  ///< communication lost: a peer node's heartbeat stopped (peer_heartbeat_timeout_s)
};

/// Name of a cause ("sensor NaN", ...). @rt
[[nodiscard]] const char* supervisorCauseName(SupervisorCause cause) noexcept;

enum class SupervisorState : std::uint8_t { kStartup, kRunning, kTripped };

/// One supervisor event.
struct SupervisorEvent {
  std::uint64_t tick = 0;
  double t_s = 0.0;
  SupervisorCause cause = SupervisorCause::kNone;
  bool trip = false;  ///< true for a trip (latched), false for an information event
  int joint = -1;     ///< device joint concerned, -1 for none
  double value = std::numeric_limits<double>::quiet_NaN();  ///< the offending value (SI units)
};

/// Constant description of what is supervised: the parameters and each device joint's limits.
struct SupervisorModel {
  SupervisorParams params;
  int n = 0;  ///< device joints
  IoVector min_rad, max_rad, velocity_limit_radps, torque_limit_nm, valve_limit_v;
  double period_s = 1e-3;
};

/// Builds the model for the device joints `joints` of `model`; valve limits per device joint.
/// @throws std::invalid_argument for inconsistent sizes or parameters
[[nodiscard]] SupervisorModel makeSupervisorModel(const SupervisorParams& params, const arm::ArmModel& model,
                                                  const arm::JointSelection& joints, const IoVector& valve_limit_v,
                                                  double period_s);

/// External requests of one tick.
struct SupervisorRequests {
  bool estop_command = false;      ///< E-stop requested by a command
  bool estop_signal = false;       ///< a signal asked the program to stop
  bool reset_command = false;      ///< explicit reset of a latched trip
  bool overrun_fault = false;      ///< the loop saw too many consecutive overruns
  std::uint64_t heartbeat = 0;     ///< a counter the supervising side increments
  bool heartbeat_enabled = false;  ///< false: no heartbeat is watched
  /// A peer node's heartbeat has not come for peer_heartbeat_timeout_s (the side that receives
  /// it decides): communication lost.
  bool peer_heartbeat_lost = false;
};

/// Largest number of events recorded in one tick.
inline constexpr int kMaxEventsPerTick = 8;

struct SupervisorData {
  SupervisorState state = SupervisorState::kStartup;
  SupervisorCause trip_cause = SupervisorCause::kNone;  ///< cause of the latched trip
  double startup_valid_since_s = std::numeric_limits<double>::quiet_NaN();
  IoVector q_previous, qd_filtered_radps;
  bool have_previous = false;
  std::uint64_t heartbeat_value = 0;
  double heartbeat_changed_s = 0.0;
  bool heartbeat_seen = false;
  /// Contact fade: 1 = full contact forces, 0 = none.
  double contact_scale = 1.0;
  bool fading = false;
  bool fade_limiting = false;  ///< the rate bound held a joint back in the last tick
  /// Contact torques after the fade of the previous tick (configuration vector) [N m].
  Eigen::Matrix<double, Eigen::Dynamic, 1, 0, arm::kMaxJoints, 1> tau_contact_previous_nm;
  /// Events of the current tick (the tick copies them to its telemetry record).
  std::array<SupervisorEvent, kMaxEventsPerTick> events{};
  int num_events = 0;
  std::uint64_t trips = 0;  ///< trips since reset
  std::uint64_t tick = 0;
  double t_s = 0.0;
};

/// Back to kStartup with no history; `n_config` is the configuration size. @rt
void resetSupervisor(const SupervisorModel& model, SupervisorData& data, int n_config) noexcept;

/// First step of a tick: clears the tick's events, applies the requests (E-stop, reset,
/// overrun, heartbeat) and checks the reading. Returns true when forces are allowed this tick
/// (state kRunning after the checks).
/// @param device_status status of the device's read
/// @rt
bool supervisorCheckInputs(const SupervisorModel& model, SupervisorData& data, std::uint64_t tick, double t_s,
                           const JointSample& sample, const core::RtStatus& device_status,
                           const SupervisorRequests& requests) noexcept;

/// Latches a trip with `cause` (the valves go to null from this tick on). @rt
void supervisorTrip(SupervisorData& data, SupervisorCause cause, int joint, double value) noexcept;

/// Contact fade: `seconds_since_minima` is the age of the newest adopted minima set (its
/// arrival, not its query). Scales `tau_contact_nm` (configuration vector) in place by the fade
/// and limits each joint's change to max_fade_rate_nm_per_s while fading or recovering. @rt
void supervisorFadeContact(const SupervisorModel& model, SupervisorData& data, double seconds_since_minima,
                           Eigen::Ref<Eigen::VectorXd> tau_contact_nm) noexcept;

/// Last step: trips on a valve command beyond its limit, and puts every valve at null unless
/// the state is kRunning. @rt
void supervisorLimitOutputs(const SupervisorModel& model, SupervisorData& data, IoVector& valve_v) noexcept;

}  // namespace fullarm::hil
