#include "fullarm/hil/tick.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/haptics/local_descent.hpp"

namespace fullarm::hil {

TickModel makeTickModel(const arm::ArmModel& model, const haptics::CollisionWorld& world,
                        const haptics::HapticsParams& haptics, const controllers::GainsConfig& gains,
                        const SupervisorParams& supervisor, const arm::JointSelection& device_joints,
                        const Eigen::VectorXd& fixed_posture) {
  if (&world.model() != &model) throw std::invalid_argument("tick: the collision world was built for another arm model");
  if (fixed_posture.size() != model.numJoints()) throw std::invalid_argument("tick: posture of the wrong size");
  if (device_joints.numModelJoints() != model.numJoints()) {
    throw std::invalid_argument("tick: the device's joint selection is for another arm model");
  }
  TickModel t;
  t.model = &model;
  t.world = &world;
  t.haptics = haptics;
  t.controller = controllers::makeArmControllerModel(gains, model);
  t.device_joints = device_joints;
  t.fixed_posture = fixed_posture;
  t.period_s = gains.control_period_s;
  IoVector valve_limit = IoVector::Constant(device_joints.size(), 0.0);
  for (int k = 0; k < t.controller.numJoints(); ++k) {
    const int position = device_joints.position(t.controller.selection.modelIndex(k));
    if (position < 0) {
      throw core::ConfigError(gains.source, "joints[" + std::to_string(k) + "].name",
                              "'" + gains.joints[static_cast<std::size_t>(k)].name +
                                  "' is controlled but the I/O device does not serve it");
    }
    t.device_of_controller[static_cast<std::size_t>(k)] = position;
    valve_limit[position] = gains.joints[static_cast<std::size_t>(k)].valve_limit_v;
  }
  t.supervisor = makeSupervisorModel(supervisor, model, device_joints, valve_limit, t.period_s);
  for (int l = 0; l < model.numJoints() && l < arm::kMaxJoints; ++l) {
    double extent = 0.0;
    // The farthest point of the link's geometry from its frame's origin: a vertex of a mesh
    // link, or a segment end plus the radius of a capsule link.
    if (world.linkShape(l) == haptics::LinkShape::kMesh) {
      const haptics::TriMesh& mesh = world.linkMesh(l);
      for (int v = 0; v < mesh.numVertices(); ++v) extent = std::max(extent, mesh.vertex(v).norm());
    } else if (world.linkShape(l) == haptics::LinkShape::kCapsule) {
      const haptics::Capsule& capsule = world.linkCapsule(l);
      extent = std::max(capsule.a_m.norm(), capsule.b_m.norm()) + capsule.radius_m;
    }
    t.link_extent_m[static_cast<std::size_t>(l)] = extent;
  }
  t.sweep_limit_m = haptics.cutoff_m - haptics.force_threshold_m;
  return t;
}

TickData::TickData(const TickModel& model)
    : fk(*model.model),
      query_fk(*model.model),
      contact(*model.model, kMaxTrackedMinima),
      tracked(static_cast<std::size_t>(kMaxTrackedMinima)),
      q(model.fixed_posture),
      tau_contact_nm(Eigen::VectorXd::Zero(model.model->numJoints())) {
  load_cells_nm = controllers::ControlVector::Zero(model.controller.numJoints());
  valve_controller_v = controllers::ControlVector::Zero(model.controller.numJoints());
  valve_v = IoVector::Zero(model.device_joints.size());
  resetTick(model, *this);
}

void resetTick(const TickModel& tick, TickData& data) noexcept {
  data.num_tracked = 0;
  data.tick = 0;
  data.minima_set_id = -1;
  data.minima_age_s = 0.0;
  data.have_query = false;
  data.sweep_m.fill(0.0);
  data.controller_running = false;
  data.control = controllers::ArmControllerData{};
  data.q = tick.fixed_posture;
  data.tau_contact_nm.setZero();
  data.valve_v.setZero();
  haptics::resetContactRecords(data.contact);
  resetSupervisor(tick.supervisor, data.supervisor, tick.model->numJoints());
}

namespace {

void adopt(const TickModel& tick, TickData& data, const MinimaDelivery& delivery) noexcept {
  const int n = static_cast<int>(std::min<std::size_t>(delivery.minima.size(), kMaxTrackedMinima));
  // The search's set replaces the tracked one: it holds every pair within L at its query.
  for (int i = 0; i < n; ++i) data.tracked[static_cast<std::size_t>(i)] = delivery.minima[static_cast<std::size_t>(i)];
  data.num_tracked = n;
  data.minima_set_id = delivery.set_id;
  data.minima_age_s = 0.0;
  // Link frames at the query's joint angles: the reference of the sweep bound.
  if (static_cast<int>(delivery.query_q_rad.size()) == tick.model->numJoints()) {
    const Eigen::Map<const Eigen::VectorXd> q_query(delivery.query_q_rad.data(), tick.model->numJoints());
    data.query_fk.q = q_query;
    arm::computeForwardKinematics(*tick.model, data.query_fk, data.query_fk.q);
    data.have_query = true;
  } else {
    data.have_query = false;
  }
}

void updateSweep(const TickModel& tick, TickData& data) noexcept {
  const int links = std::min(tick.model->numJoints(), arm::kMaxJoints);
  for (int l = 0; l < links; ++l) {
    double sweep = 0.0;
    if (data.have_query) {
      const Eigen::Isometry3d& now = data.fk.X_WL[static_cast<std::size_t>(l)];
      const Eigen::Isometry3d& then = data.query_fk.X_WL[static_cast<std::size_t>(l)];
      // Every point at distance r from the link origin moved at most |do| + |R_now R_then^T - I| r,
      // and that matrix norm is 2 sin(theta/2) = sqrt(3 - trace) for the rotation angle theta.
      const double trace = (now.linear() * then.linear().transpose()).trace();
      const double chord = std::sqrt(std::max(0.0, 3.0 - trace));
      sweep = (now.translation() - then.translation()).norm() + chord * tick.link_extent_m[static_cast<std::size_t>(l)];
    }
    data.sweep_m[static_cast<std::size_t>(l)] = sweep;
  }
}

void fillTelemetry(const TickModel& tick, const TickData& data, const TickInputs& inputs, bool forces_allowed,
                   TickTelemetry& t) noexcept {
  const JointSample& s = *inputs.sample;
  const int nd = tick.device_joints.size();
  const int nc = std::min(tick.model->numJoints(), arm::kMaxJoints);
  t.tick = data.tick;
  t.t_s = static_cast<double>(data.tick) * tick.period_s;
  t.sample_t_s = s.t_s;
  t.sample_sequence = s.sequence;
  t.num_device_joints = nd;
  t.num_config = nc;
  for (int k = 0; k < nd; ++k) {
    t.q_rad[static_cast<std::size_t>(k)] = k < s.q_rad.size() ? s.q_rad[k] : std::numeric_limits<double>::quiet_NaN();
    t.tau_load_cell_nm[static_cast<std::size_t>(k)] =
        k < s.tau_load_cell_nm.size() ? s.tau_load_cell_nm[k] : std::numeric_limits<double>::quiet_NaN();
    t.valve_v[static_cast<std::size_t>(k)] = data.valve_v[k];
  }
  t.link_contact_mask = 0;
  t.link_penetration_mask = 0;
  t.sweep_exceeded_mask = 0;
  for (int l = 0; l < nc; ++l) {
    const std::size_t i = static_cast<std::size_t>(l);
    t.tau_contact_nm[i] = data.tau_contact_nm[l];
    t.tau_gravity_nm[i] = data.fk.tau_gravity[l];
    const haptics::LinkContactRecord& r = data.contact.links[i];
    t.link_min_distance_m[i] = r.min_distance_m;
    t.link_depth_m[i] = r.depth_m;
    t.link_sweep_m[i] = data.sweep_m[i];
    const Eigen::Vector3d& f = data.contact.link_force_W[i];
    t.link_force_W_n[i] = {f.x(), f.y(), f.z()};
    t.link_contact_s[i] = r.contact_duration_s;
    t.link_penetration_s[i] = r.total_penetration_s;
    if (r.in_contact) t.link_contact_mask |= 1u << l;
    if (r.penetrating) t.link_penetration_mask |= 1u << l;
    if (data.sweep_m[i] > tick.sweep_limit_m) t.sweep_exceeded_mask |= 1u << l;
  }
  t.tracked_minima = data.num_tracked;
  t.active_springs = data.contact.active_springs;
  t.minima_set_id = data.minima_set_id;
  t.adopted_this_tick = inputs.minima != nullptr;
  t.minima_age_s = data.minima_age_s;
  t.contact_scale = data.supervisor.contact_scale;
  t.supervisor_state = data.supervisor.state;
  t.trip_cause = data.supervisor.trip_cause;
  t.forces_allowed = forces_allowed;
  t.controller_faults = data.control.status.faults;
  t.num_events = data.supervisor.num_events;
  for (int i = 0; i < data.supervisor.num_events; ++i) {
    t.events[static_cast<std::size_t>(i)] = data.supervisor.events[static_cast<std::size_t>(i)];
  }
}

}  // namespace

void stepTick(const TickModel& tick, TickData& data, const TickInputs& inputs, IoVector& valve_v,
              TickTelemetry& telemetry) noexcept {
  const arm::ArmModel& model = *tick.model;
  const JointSample& sample = *inputs.sample;
  ++data.tick;
  const double t_s = static_cast<double>(data.tick) * tick.period_s;
  data.minima_age_s += tick.period_s;

  // Input checks.
  bool running = supervisorCheckInputs(tick.supervisor, data.supervisor, data.tick, t_s, sample,
                                       inputs.device_status, inputs.requests);
  const bool readable = inputs.device_status.ok() && sample.q_rad.size() == tick.device_joints.size() &&
                        sample.tau_load_cell_nm.size() == tick.device_joints.size() && sample.q_rad.allFinite() &&
                        sample.tau_load_cell_nm.allFinite();

  if (inputs.minima != nullptr) adopt(tick, data, *inputs.minima);

  data.valve_controller_v.setZero();
  if (readable) {
    tick.device_joints.scatter(sample.q_rad, data.q);
    // Forward kinematics once; every piece below reads it.
    arm::computeForwardKinematics(model, data.fk, data.q);
    // Local descent of the tracked minima to the new link poses.
    data.num_tracked =
        haptics::updateMinimaLocalDescent(*tick.world, data.fk,
                                          std::span<haptics::LocalMinimum>(data.tracked.data(),
                                                                           static_cast<std::size_t>(data.num_tracked)),
                                          tick.haptics.descent);
    const std::span<const haptics::LocalMinimum> live(data.tracked.data(), static_cast<std::size_t>(data.num_tracked));
    updateSweep(tick, data);
    // Contact springs and the tailored Jacobian torques, Eq. (1)-(2).
    haptics::computeContactForces(tick.haptics, model, data.fk, live, tick.period_s, data.contact);
    haptics::computeContactTorques(model, data.fk, live, data.contact);
    if (!data.contact.status.ok()) supervisorTrip(data.supervisor, SupervisorCause::kContactFault, -1, 0.0);
    // Gravity once, from the same kinematics.
    arm::computeGravityTorquesAtKinematics(model, data.fk);
    data.tau_contact_nm = data.contact.tau_contact_nm;
    supervisorFadeContact(tick.supervisor, data.supervisor, data.minima_age_s, data.tau_contact_nm);

    running = data.supervisor.state == SupervisorState::kRunning;
    if (running) {
      // The admittance controller starts at rest at the first tick with forces allowed.
      if (!data.controller_running) {
        controllers::resetArmController(tick.controller, data.control, data.q);
        data.controller_running = true;
      }
      for (int k = 0; k < tick.controller.numJoints(); ++k) {
        data.load_cells_nm[k] = sample.tau_load_cell_nm[tick.device_of_controller[static_cast<std::size_t>(k)]];
      }
      controllers::stepArmController(tick.controller, data.control, data.q, data.fk.tau_gravity, data.tau_contact_nm,
                                     data.load_cells_nm, data.valve_controller_v);
      if (!data.control.status.ok()) supervisorTrip(data.supervisor, SupervisorCause::kControllerFault, -1, 0.0);
    }
  }
  if (data.supervisor.state != SupervisorState::kRunning) data.controller_running = false;

  // Output limits.
  data.valve_v.setZero();
  for (int k = 0; k < tick.controller.numJoints(); ++k) {
    data.valve_v[tick.device_of_controller[static_cast<std::size_t>(k)]] = data.valve_controller_v[k];
  }
  supervisorLimitOutputs(tick.supervisor, data.supervisor, data.valve_v);
  valve_v = data.valve_v;
  fillTelemetry(tick, data, inputs, data.supervisor.state == SupervisorState::kRunning, telemetry);
}

}  // namespace fullarm::hil
