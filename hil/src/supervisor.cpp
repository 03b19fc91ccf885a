#include "fullarm/hil/supervisor.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace fullarm::hil {

const char* supervisorCauseName(SupervisorCause cause) noexcept {
  switch (cause) {
    case SupervisorCause::kNone:
      return "none";
    case SupervisorCause::kSensorNonFinite:
      return "sensor reading not finite";
    case SupervisorCause::kSensorOutOfRange:
      return "sensor reading out of range";
    case SupervisorCause::kSensorRate:
      return "implausible sensor rate";
    case SupervisorCause::kPositionLimit:
      return "joint position limit";
    case SupervisorCause::kVelocityLimit:
      return "joint velocity limit";
    case SupervisorCause::kTorqueLimit:
      return "load-cell torque limit";
    case SupervisorCause::kValveCommandLimit:
      return "valve command beyond its limit";
    case SupervisorCause::kEstopCommand:
      return "E-stop command";
    case SupervisorCause::kEstopSignal:
      return "E-stop signal";
    case SupervisorCause::kHeartbeatLost:
      return "heartbeat lost";
    case SupervisorCause::kOverrun:
      return "loop overruns";
    case SupervisorCause::kDeviceFault:
      return "I/O device fault";
    case SupervisorCause::kControllerFault:
      return "controller fault";
    case SupervisorCause::kContactFault:
      return "contact computation fault";
    case SupervisorCause::kStartupComplete:
      return "start-up guard released";
    case SupervisorCause::kMinimaStale:
      return "global minima stale: contact forces fading";
    case SupervisorCause::kMinimaFresh:
      return "fresh global minima: contact forces restored";
    case SupervisorCause::kReset:
      return "reset by command";
    case SupervisorCause::kCommunicationLost:
      return "communication lost";
    case SupervisorCause::kPeerHeartbeatLost:
      return "communication lost: a peer node's heartbeat stopped";
  }
  return "unknown";
}

SupervisorModel makeSupervisorModel(const SupervisorParams& params, const arm::ArmModel& model,
                                    const arm::JointSelection& joints, const IoVector& valve_limit_v,
                                    double period_s) {
  if (valve_limit_v.size() != joints.size()) throw std::invalid_argument("supervisor: one valve limit per joint");
  if (!(period_s > 0.0)) throw std::invalid_argument("supervisor: the control period must be positive");
  SupervisorModel m;
  m.params = params;
  m.n = joints.size();
  m.period_s = period_s;
  m.min_rad.resize(m.n);
  m.max_rad.resize(m.n);
  m.velocity_limit_radps.resize(m.n);
  m.torque_limit_nm.resize(m.n);
  m.valve_limit_v = valve_limit_v;
  for (int k = 0; k < m.n; ++k) {
    const arm::JointLimits& lim = model.joints[static_cast<std::size_t>(joints.modelIndex(k))].limits;
    m.min_rad[k] = lim.min_rad;
    m.max_rad[k] = lim.max_rad;
    m.velocity_limit_radps[k] = lim.velocity_radps;
    m.torque_limit_nm[k] = lim.torque_nm;
  }
  return m;
}

namespace {

void record(SupervisorData& data, SupervisorCause cause, bool trip, int joint, double value) noexcept {
  if (data.num_events >= kMaxEventsPerTick) return;
  SupervisorEvent& e = data.events[static_cast<std::size_t>(data.num_events++)];
  e.tick = data.tick;
  e.t_s = data.t_s;
  e.cause = cause;
  e.trip = trip;
  e.joint = joint;
  e.value = value;
}

}  // namespace

void resetSupervisor(const SupervisorModel& model, SupervisorData& data, int n_config) noexcept {
  data.state = SupervisorState::kStartup;
  data.trip_cause = SupervisorCause::kNone;
  data.startup_valid_since_s = std::numeric_limits<double>::quiet_NaN();
  data.q_previous = IoVector::Zero(model.n);
  data.qd_filtered_radps = IoVector::Zero(model.n);
  data.have_previous = false;
  data.heartbeat_seen = false;
  data.contact_scale = 1.0;
  data.fading = false;
  data.fade_limiting = false;
  data.tau_contact_previous_nm.setZero(n_config);
  data.num_events = 0;
  data.trips = 0;
}

void supervisorTrip(SupervisorData& data, SupervisorCause cause, int joint, double value) noexcept {
  if (data.state == SupervisorState::kTripped) return;  // latched: the first cause stays
  data.state = SupervisorState::kTripped;
  data.trip_cause = cause;
  ++data.trips;
  record(data, cause, true, joint, value);
}

bool supervisorCheckInputs(const SupervisorModel& model, SupervisorData& data, std::uint64_t tick, double t_s,
                           const JointSample& sample, const core::RtStatus& device_status,
                           const SupervisorRequests& requests) noexcept {
  const SupervisorParams& p = model.params;
  data.num_events = 0;
  data.tick = tick;
  data.t_s = t_s;

  if (requests.reset_command && data.state == SupervisorState::kTripped) {
    data.state = SupervisorState::kStartup;
    data.trip_cause = SupervisorCause::kNone;
    data.startup_valid_since_s = std::numeric_limits<double>::quiet_NaN();
    data.have_previous = false;
    record(data, SupervisorCause::kReset, false, -1, std::numeric_limits<double>::quiet_NaN());
  }
  if (requests.estop_command) supervisorTrip(data, SupervisorCause::kEstopCommand, -1, 0.0);
  if (requests.estop_signal) supervisorTrip(data, SupervisorCause::kEstopSignal, -1, 0.0);
  if (requests.overrun_fault) supervisorTrip(data, SupervisorCause::kOverrun, -1, 0.0);
  if (requests.heartbeat_enabled) {
    if (!data.heartbeat_seen || requests.heartbeat != data.heartbeat_value) {
      data.heartbeat_seen = true;
      data.heartbeat_value = requests.heartbeat;
      data.heartbeat_changed_s = t_s;
    } else if (t_s - data.heartbeat_changed_s > p.heartbeat_timeout_s) {
      supervisorTrip(data, SupervisorCause::kHeartbeatLost, -1, t_s - data.heartbeat_changed_s);
    }
  }
  if (requests.peer_heartbeat_lost) {
    supervisorTrip(data, SupervisorCause::kPeerHeartbeatLost, -1, p.peer_heartbeat_timeout_s);
  }
  if (!device_status.ok()) {
    const bool link = (device_status.faults & kFaultLinkLost) != 0;
    supervisorTrip(data, link ? SupervisorCause::kCommunicationLost : SupervisorCause::kDeviceFault, -1, 0.0);
  }

  // The reading.
  bool valid = device_status.ok() && sample.q_rad.size() == model.n && sample.tau_load_cell_nm.size() == model.n;
  bool inside = true;
  const double a = std::exp(-2.0 * std::numbers::pi * p.velocity_filter_hz * model.period_s);
  for (int k = 0; valid && k < model.n; ++k) {
    const double q = sample.q_rad[k];
    const double tau = sample.tau_load_cell_nm[k];
    if ((sample.out_of_range_mask >> k) & 1u) {
      supervisorTrip(data, SupervisorCause::kSensorOutOfRange, k, std::isnan(q) ? tau : q);
      valid = false;
      break;
    }
    if (!std::isfinite(q) || !std::isfinite(tau)) {
      supervisorTrip(data, SupervisorCause::kSensorNonFinite, k, std::isfinite(q) ? tau : q);
      valid = false;
      break;
    }
    if (q < model.min_rad[k] - p.position_margin_rad || q > model.max_rad[k] + p.position_margin_rad) {
      supervisorTrip(data, SupervisorCause::kPositionLimit, k, q);
    }
    if (std::abs(tau) > p.torque_limit_factor * model.torque_limit_nm[k]) {
      supervisorTrip(data, SupervisorCause::kTorqueLimit, k, tau);
    }
    if (q < model.min_rad[k] || q > model.max_rad[k]) inside = false;
    if (data.have_previous) {
      const double rate = (q - data.q_previous[k]) / model.period_s;
      if (std::abs(rate) > p.max_plausible_rate_radps) {
        supervisorTrip(data, SupervisorCause::kSensorRate, k, rate);
      }
      data.qd_filtered_radps[k] = a * data.qd_filtered_radps[k] + (1.0 - a) * rate;
      if (std::abs(data.qd_filtered_radps[k]) > p.velocity_limit_factor * model.velocity_limit_radps[k]) {
        supervisorTrip(data, SupervisorCause::kVelocityLimit, k, data.qd_filtered_radps[k]);
      }
    }
  }
  if (valid) {
    data.q_previous = sample.q_rad;
    data.have_previous = true;
  } else {
    data.have_previous = false;
  }

  // Start-up guard.
  if (data.state == SupervisorState::kStartup) {
    if (!valid || !inside) {
      data.startup_valid_since_s = std::numeric_limits<double>::quiet_NaN();
    } else if (std::isnan(data.startup_valid_since_s)) {
      data.startup_valid_since_s = t_s;
    }
    if (!std::isnan(data.startup_valid_since_s) && t_s - data.startup_valid_since_s >= p.startup_valid_s) {
      data.state = SupervisorState::kRunning;
      record(data, SupervisorCause::kStartupComplete, false, -1, t_s - data.startup_valid_since_s);
    }
  }
  return data.state == SupervisorState::kRunning;
}

void supervisorFadeContact(const SupervisorModel& model, SupervisorData& data, double seconds_since_minima,
                           Eigen::Ref<Eigen::VectorXd> tau_contact_nm) noexcept {
  const SupervisorParams& p = model.params;
  const bool stale = seconds_since_minima > p.stale_global_periods * p.global_period_s;
  if (stale && !data.fading) {
    data.fading = true;
    record(data, SupervisorCause::kMinimaStale, false, -1, seconds_since_minima);
  } else if (!stale && data.fading) {
    data.fading = false;
    record(data, SupervisorCause::kMinimaFresh, false, -1, seconds_since_minima);
  }
  const double step = p.fade_s > 0.0 ? model.period_s / p.fade_s : 1.0;
  // The rate bound holds while fading, while coming back, and until the output has caught up.
  const bool in_transition = data.fading || data.contact_scale < 1.0 || data.fade_limiting;
  if (data.fading) {
    data.contact_scale = std::max(0.0, data.contact_scale - step);
  } else if (data.contact_scale < 1.0) {
    data.contact_scale = std::min(1.0, data.contact_scale + step);
  }
  const double max_step = p.max_fade_rate_nm_per_s * model.period_s;
  data.fade_limiting = false;
  for (Eigen::Index i = 0; i < tau_contact_nm.size(); ++i) {
    double tau = data.contact_scale * tau_contact_nm[i];
    if (in_transition && i < data.tau_contact_previous_nm.size()) {
      const double prev = data.tau_contact_previous_nm[i];
      const double limited = std::clamp(tau, prev - max_step, prev + max_step);
      data.fade_limiting = data.fade_limiting || limited != tau;
      tau = limited;
    }
    tau_contact_nm[i] = tau;
    if (i < data.tau_contact_previous_nm.size()) data.tau_contact_previous_nm[i] = tau;
  }
}

void supervisorLimitOutputs(const SupervisorModel& model, SupervisorData& data, IoVector& valve_v) noexcept {
  for (int k = 0; k < model.n && k < valve_v.size(); ++k) {
    const double v = valve_v[k];
    if (!std::isfinite(v) || std::abs(v) > model.valve_limit_v[k] + model.params.valve_limit_tolerance_v) {
      supervisorTrip(data, SupervisorCause::kValveCommandLimit, k, v);
    }
  }
  if (data.state != SupervisorState::kRunning) valve_v.setZero();
}

}  // namespace fullarm::hil
