#pragma once
/// @file
/// IoDevice: the arm's inputs and outputs in physical units, behind one lifecycle
/// (configure -> activate -> deactivate), with the safety policy every back-end shares:
///
///  - The safe output of a servovalve is null (0 V), which locks the joints hydraulically: the
///    user stays strapped into a rigid arm, not a limp one. On any fault, while inactive and
///    before activation the device applies its own safe outputs, never "hold the last command".
///  - Activation never applies a stale command: the device keeps no command across activate()
///    and deactivate(); the first write() after activate() puts out the safe output whatever it
///    is given, and the commands ramp in linearly from there over IoSafetyParams::ramp_in_s.
///  - Back-ends with an enable line (Comedi) toggle it on every write() while active and not
///    faulted: a heartbeat for an external hardware watchdog (amplifier enable or pressure
///    dump), the only thing that can make the arm safe when the process dies, because Comedi's
///    analog outputs hold their last value then (docs/hil.md, "What the rig must provide").
///
/// The joints of a device are an arm::JointSelection (its subset vectors follow the selection's
/// order, arm/joint_selection.hpp).

#include <Eigen/Core>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/joint_selection.hpp"
#include "fullarm/core/rt_status.hpp"

namespace fullarm::hil {

/// Largest number of joints a device serves.
inline constexpr int kMaxIoJoints = arm::kMaxJoints;

/// Fixed-capacity per-device-joint vector (no heap).
using IoVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxIoJoints, 1>;

/// The fault bits of the hil module (core::RtStatus::faults), beside core's.
enum HilFault : std::uint32_t {
  kFaultDeviceRead = 1u << 16,     ///< the device could not read its inputs
  kFaultDeviceWrite = 1u << 17,    ///< the device could not write its outputs
  kFaultDeviceState = 1u << 18,    ///< read or write in a lifecycle state that does not allow it
  kFaultDeviceLatched = 1u << 19,  ///< the device was put in its fault state (fault())
  kFaultLinkLost = 1u << 20,       ///< a remote device's node stopped answering (lcm_io.hpp)
};

/// A device that cannot be opened or does not match its channel map (a missing board, a channel
/// or range the board does not have, a map that serves other joints than the tick's): bad input
/// to a run, reported before the device is activated.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One reading of every joint of a device, after calibration.
struct JointSample {
  double t_s = 0.0;            ///< device time of the reading [s]
  std::uint64_t sequence = 0;  ///< counts the reads since configure()
  IoVector q_rad;              ///< joint angles [rad], device order
  IoVector tau_load_cell_nm;   ///< load-cell torques [N m], device order
  /// Bit k: a reading of joint k was at an end of its converter's range (Comedi reports it out
  /// of range; the value is then NaN).
  std::uint32_t out_of_range_mask = 0;
  /// Chamber pressures [Pa, gauge], device order, where the back-end reads them: bit k of
  /// `pressure_mask` says joint k's were read (the simulated DTS with pressure transducers in
  /// its plant file; on a board, the joints whose channel map wires them: the DTS master itself
  /// has none). NaN where a board's code is at a converter range end (the plant's own
  /// transducers clamp instead); that does not set out_of_range_mask.
  IoVector p_a_pa;
  IoVector p_b_pa;
  std::uint32_t pressure_mask = 0;
};

/// Lifecycle state of a device.
enum class IoState : std::uint8_t {
  kUnconfigured,  ///< nothing opened
  kInactive,      ///< configured: readable, outputs at their safe value, enable line still
  kActive,        ///< commands reach the outputs (after the ramp-in)
  kFault,         ///< safe outputs, enable line still, until clearFault()
};

/// Name of a state ("inactive", ...).
[[nodiscard]] const char* ioStateName(IoState state) noexcept;

/// The safety policy shared by every back-end.
struct IoSafetyParams {
  /// Commands ramp from the safe output to full scale over this time after activation [s]
  /// (0: the second write after activation already passes the command through).
  double ramp_in_s = 0.5;
  /// The device clamps every command to +-this [V] (the last line of defence; the supervisor
  /// trips before it).
  double valve_limit_v = 10.0;
};

/// Base class of the back-ends (sim, comedi, fakedaq). Not thread-safe: one thread drives it.
class IoDevice {
 public:
  virtual ~IoDevice() = default;
  IoDevice(const IoDevice&) = delete;
  IoDevice& operator=(const IoDevice&) = delete;

  /// Opens and checks the hardware (or builds the simulation): kUnconfigured -> kInactive.
  /// The outputs are put at their safe value.
  /// @throws core::ConfigError or std::runtime_error naming the device, the file and the key
  ///   when the device is missing, unreadable or does not match its channel map.
  void configure();
  /// kInactive -> kActive. Forgets any command: the next write() puts out the safe output and
  /// the commands ramp in from there. No effect when already active.
  /// @throws std::logic_error when not configured or in the fault state (clearFault() first).
  void activate();
  /// Safe outputs, enable line still; kActive -> kInactive (no effect in other states).
  void deactivate() noexcept;
  /// Puts the device in its fault state: safe outputs now and on every later write(), enable
  /// line still. The cause (a string literal) is kept in status(). @rt
  void fault(const char* cause) noexcept;
  /// kFault -> kInactive (an explicit operator action; activate() again to drive the arm).
  void clearFault() noexcept;

  /// Reads every joint. Allowed from kInactive on. A back-end failure returns a non-ok status
  /// with kFaultDeviceRead and puts the device in its fault state.
  /// @rt for hardware back-ends; the simulated ones advance their plant here (allocation-free,
  /// unbounded time, core/rt_status.hpp).
  core::RtStatus read(JointSample& sample) noexcept;
  /// Writes the valve commands [V], device order. Active: clamped to +-valve_limit_v and scaled
  /// by the ramp-in; otherwise (inactive, fault, unconfigured) the safe output is written
  /// instead. A back-end failure puts the device in its fault state. @rt
  core::RtStatus write(const IoVector& valve_v) noexcept;

  [[nodiscard]] IoState state() const noexcept { return state_; }
  /// The joints of the device (their order is the order of every subset vector).
  [[nodiscard]] const arm::JointSelection& joints() const noexcept { return joints_; }
  [[nodiscard]] int numJoints() const noexcept { return joints_.size(); }
  /// Control period the device expects between two reads [s].
  [[nodiscard]] double period() const noexcept { return period_s_; }
  /// The command the device put out last, after clamping and ramp-in [V], device order.
  [[nodiscard]] const IoVector& appliedCommand() const noexcept { return applied_v_; }
  /// True when the last write() toggled the enable line (active and not faulted).
  [[nodiscard]] bool enableAsserted() const noexcept { return enable_; }
  /// Ramp-in factor of the last write() (0 right after activation, 1 once ramped in).
  [[nodiscard]] double rampFactor() const noexcept { return ramp_; }
  /// First fault since configure() (or clearFault()), ok otherwise.
  [[nodiscard]] const core::RtStatus& status() const noexcept { return status_; }
  [[nodiscard]] const IoSafetyParams& safety() const noexcept { return safety_; }
  /// Back-end name ("sim", "comedi", "fakedaq").
  [[nodiscard]] virtual std::string_view name() const noexcept = 0;

 protected:
  IoDevice(arm::JointSelection joints, double period_s, const IoSafetyParams& safety);
  /// The plant node serves a remote device's back-end directly: the lifecycle and the safety
  /// policy already ran on the remote side (lcm_io.hpp).
  friend class LcmPlantNode;

  /// Back-end hooks. onConfigure may throw; the others must not.
  virtual void onConfigure() = 0;
  virtual void onActivate() noexcept {}
  virtual void onDeactivate() noexcept {}
  /// Fills q_rad, tau_load_cell_nm (sized numJoints()), t_s and out_of_range_mask, and where the
  /// back-end reads chamber pressures p_a_pa, p_b_pa (sized numJoints()) and pressure_mask
  /// (reset to 0 before every call).
  virtual core::RtStatus onRead(JointSample& sample) noexcept = 0;
  /// Puts `valve_v` (already limited) on the outputs; `toggle_enable` is true when the enable
  /// line must change state (a heartbeat), false when it must stay as it is.
  virtual core::RtStatus onWrite(const IoVector& valve_v, bool toggle_enable) noexcept = 0;

 private:
  void writeSafe() noexcept;

  arm::JointSelection joints_;
  double period_s_;
  IoSafetyParams safety_;
  IoState state_ = IoState::kUnconfigured;
  core::RtStatus status_;
  std::uint64_t reads_ = 0;
  std::uint64_t writes_since_activation_ = 0;
  IoVector applied_v_;
  IoVector zero_v_;
  double ramp_ = 0.0;
  bool enable_ = false;
};

}  // namespace fullarm::hil
