#include "fullarm/hil/io_device.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace fullarm::hil {

const char* ioStateName(IoState state) noexcept {
  switch (state) {
    case IoState::kUnconfigured:
      return "unconfigured";
    case IoState::kInactive:
      return "inactive";
    case IoState::kActive:
      return "active";
    case IoState::kFault:
      return "fault";
  }
  return "unknown";
}

IoDevice::IoDevice(arm::JointSelection joints, double period_s, const IoSafetyParams& safety)
    : joints_(std::move(joints)), period_s_(period_s), safety_(safety) {
  if (!(period_s > 0.0)) throw std::invalid_argument("IoDevice: the control period must be positive");
  if (!(safety.valve_limit_v > 0.0)) throw std::invalid_argument("IoDevice: valve_limit_v must be positive");
  if (!(safety.ramp_in_s >= 0.0)) throw std::invalid_argument("IoDevice: ramp_in_s must be >= 0");
  applied_v_ = IoVector::Zero(joints_.size());
  zero_v_ = IoVector::Zero(joints_.size());
}

void IoDevice::configure() {
  onConfigure();
  state_ = IoState::kInactive;
  status_.clear();
  reads_ = 0;
  writeSafe();
}

void IoDevice::activate() {
  if (state_ == IoState::kActive) return;
  if (state_ != IoState::kInactive) {
    throw std::logic_error(std::string("IoDevice ") + std::string(name()) + ": activate() in state " +
                           ioStateName(state_) + " (configure it, or clear its fault, first)");
  }
  // No command survives activation: the ramp starts from the safe output at the next write().
  writes_since_activation_ = 0;
  ramp_ = 0.0;
  state_ = IoState::kActive;
  onActivate();
}

void IoDevice::deactivate() noexcept {
  if (state_ != IoState::kActive) return;
  state_ = IoState::kInactive;
  writeSafe();
  onDeactivate();
}

void IoDevice::fault(const char* cause) noexcept {
  status_.raise(core::RtCode::kBadState, kFaultDeviceLatched, cause);
  if (state_ == IoState::kUnconfigured) return;
  state_ = IoState::kFault;
  writeSafe();
}

void IoDevice::clearFault() noexcept {
  if (state_ != IoState::kFault) return;
  status_.clear();
  state_ = IoState::kInactive;
  writeSafe();
}

void IoDevice::writeSafe() noexcept {
  applied_v_ = zero_v_;
  ramp_ = 0.0;
  enable_ = false;
  if (state_ == IoState::kUnconfigured) return;
  // A failing write of the safe output cannot be made safer here: the enable line stays still,
  // so the hardware watchdog drops the amplifiers.
  (void)onWrite(zero_v_, false);
}

core::RtStatus IoDevice::read(JointSample& sample) noexcept {
  if (state_ == IoState::kUnconfigured) {
    return core::RtStatus::fault(core::RtCode::kNotConfigured, kFaultDeviceState, "device read before configure");
  }
  sample.pressure_mask = 0;  // a back-end that reads pressures sets its bits
  const core::RtStatus s = onRead(sample);
  sample.sequence = ++reads_;
  if (!s.ok()) {
    status_.raise(s.code, s.faults | kFaultDeviceRead, s.message);
    if (state_ != IoState::kFault) {
      state_ = IoState::kFault;
      writeSafe();
    }
  }
  return s;
}

core::RtStatus IoDevice::write(const IoVector& valve_v) noexcept {
  if (state_ == IoState::kUnconfigured) {
    return core::RtStatus::fault(core::RtCode::kNotConfigured, kFaultDeviceState, "device write before configure");
  }
  if (state_ != IoState::kActive) {
    writeSafe();
    return state_ == IoState::kFault ? status_ : core::RtStatus{};
  }
  // Ramp-in: 0 at the first write after activation, 1 after ramp_in_s.
  const double ramp_writes = safety_.ramp_in_s / period_s_;
  ramp_ = ramp_writes <= 0.0 ? (writes_since_activation_ == 0 ? 0.0 : 1.0)
                             : std::min(1.0, static_cast<double>(writes_since_activation_) / ramp_writes);
  ++writes_since_activation_;
  const double limit = safety_.valve_limit_v;
  for (int k = 0; k < applied_v_.size(); ++k) {
    const double v = k < valve_v.size() ? valve_v[k] : 0.0;
    // A non-finite command is not a command: the valve goes to null.
    applied_v_[k] = std::isfinite(v) ? ramp_ * std::clamp(v, -limit, limit) : 0.0;
  }
  enable_ = true;
  const core::RtStatus s = onWrite(applied_v_, true);
  if (!s.ok()) {
    status_.raise(s.code, s.faults | kFaultDeviceWrite, s.message);
    state_ = IoState::kFault;
    writeSafe();
    return status_;
  }
  return s;
}

}  // namespace fullarm::hil
