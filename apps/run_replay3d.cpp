#include "run_replay3d.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>
#include <variant>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/hil/log_records.hpp"
#include "fullarm/hil/run_log.hpp"

namespace fullarm::app {
namespace {

std::array<double, 3> toArray(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

}  // namespace

reports::ReplayMesh replayMesh(const std::string& name, const haptics::TriMesh& mesh, const Eigen::Isometry3d& X_WO) {
  reports::ReplayMesh out;
  out.name = name;
  for (int v = 0; v < mesh.numVertices(); ++v) out.vertices_m.push_back(toArray(X_WO * mesh.vertex(v)));
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangle(t);
    out.triangles.push_back(
        {static_cast<std::uint32_t>(tri[0]), static_cast<std::uint32_t>(tri[1]), static_cast<std::uint32_t>(tri[2])});
  }
  return out;
}

std::vector<int> addReplayCapsuleLinks(const arm::ArmModel& model, reports::Replay3d& replay) {
  std::vector<int> links;
  for (int l = 0; l < model.numJoints(); ++l) {
    const arm::LinkGeometry& g = model.joints[static_cast<std::size_t>(l)].geometry;
    if (g.type == arm::LinkGeometry::Type::kCapsule) {
      links.push_back(l);
      replay.links.push_back({model.joints[static_cast<std::size_t>(l)].name, g.radius_m});
    }
  }
  return links;
}

reports::Replay3d runReplay3d(const hil::RunResult& r, const hil::HilSession& session, double frame_rate_hz) {
  const arm::ArmModel& model = session.model();
  const haptics::Scene& scene = session.scene();
  const hil::TickModel& tick = session.tickModel();
  const double period_s = session.config().control_period_s;

  reports::Replay3d replay;
  replay.title = "3D replay: the arm, the scene and the minima";

  // The scene meshes in W: X_WO = X_SW^-1 X_SO.
  const Eigen::Isometry3d X_WS = haptics::armBasePose(scene, model).inverse();
  std::vector<Eigen::Isometry3d> X_WO;
  for (const haptics::SceneObject& object : scene.objects) {
    X_WO.push_back(X_WS * object.X_SO);
    replay.meshes.push_back(replayMesh(object.name, object.mesh, X_WO.back()));
  }

  const std::vector<int> links = addReplayCapsuleLinks(model, replay);
  replay.joints = r.joint_names;

  double max_torque_nm = 0.0;
  double max_force_n = 0.0;
  for (const hil::TickTelemetry& t : r.telemetry) {
    for (int k = 0; k < tick.device_joints.size(); ++k) {
      const double tau = t.tau_contact_nm[static_cast<std::size_t>(tick.device_joints.modelIndex(k))];
      if (std::isfinite(tau)) max_torque_nm = std::max(max_torque_nm, std::abs(tau));
    }
    for (int l = 0; l < model.numJoints(); ++l) {
      const auto& f = t.link_force_W_n[static_cast<std::size_t>(l)];
      const double norm = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
      if (std::isfinite(norm)) max_force_n = std::max(max_force_n, norm);
    }
  }
  replay.torque_scale_nm = max_torque_nm > 1e-6 ? max_torque_nm : 1.0;
  replay.force_scale_n = max_force_n > 1e-6 ? max_force_n : 1.0;

  // The adopted sets in adoption order.
  std::vector<const hil::RecordedSet*> adopted;
  for (const hil::RecordedSet& set : r.sets) {
    if (set.adopted_tick >= 0) adopted.push_back(&set);
  }
  std::stable_sort(adopted.begin(), adopted.end(), [](const hil::RecordedSet* a, const hil::RecordedSet* b) {
    return a->adopted_tick < b->adopted_tick;
  });

  const std::size_t ticks = r.telemetry.size();
  const std::size_t stride =
      std::max(static_cast<std::size_t>(std::max(1.0, std::round(1.0 / (frame_rate_hz * period_s)))),
               (ticks + kMaxReplayFrames - 1) / kMaxReplayFrames);
  arm::ArmData fk(model);
  Eigen::VectorXd q = tick.fixed_posture;
  std::size_t next_set = 0;
  const hil::RecordedSet* active = nullptr;
  std::size_t window_start = 0;
  for (std::size_t k = 0; k < ticks; ++k) {
    if (!(k % stride == stride - 1 || k + 1 == ticks)) continue;
    const hil::TickTelemetry& t = r.telemetry[k];
    // Joint angles: the device's reading (NaN when the reading was not usable: keep the last).
    for (int j = 0; j < tick.device_joints.size(); ++j) {
      const double angle = t.q_rad[static_cast<std::size_t>(j)];
      if (std::isfinite(angle)) q[tick.device_joints.modelIndex(j)] = angle;
    }
    arm::computeForwardKinematics(model, fk, q);

    reports::ReplayFrame frame;
    frame.t_s = t.t_s;
    std::uint32_t touched = 0;
    for (std::size_t w = window_start; w <= k; ++w) touched |= r.telemetry[w].link_penetration_mask;
    window_start = k + 1;
    for (int l : links) {
      const arm::LinkGeometry& g = model.joints[static_cast<std::size_t>(l)].geometry;
      const Eigen::Vector3d a = arm::pointInWorld(fk, l, g.from_m);
      const Eigen::Vector3d b = arm::pointInWorld(fk, l, g.to_m);
      frame.segments_m.push_back({a.x(), a.y(), a.z(), b.x(), b.y(), b.z()});
      frame.penetrating.push_back(((touched >> l) & 1U) != 0);
    }
    for (int j = 0; j < tick.device_joints.size(); ++j) {
      const double tau = t.tau_contact_nm[static_cast<std::size_t>(tick.device_joints.modelIndex(j))];
      frame.torques_nm.push_back(std::isfinite(tau) ? tau : 0.0);
    }
    while (next_set < adopted.size() && static_cast<std::size_t>(adopted[next_set]->adopted_tick) <= k) {
      active = adopted[next_set++];
    }
    if (active != nullptr) {
      for (const haptics::LocalMinimum& m : active->minima) {
        if (m.link < 0 || m.link >= model.numJoints() || m.object < 0 ||
            static_cast<std::size_t>(m.object) >= X_WO.size())
          continue;
        const auto& f = t.link_force_W_n[static_cast<std::size_t>(m.link)];
        const double force = std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        frame.minima.push_back({toArray(arm::pointInWorld(fk, m.link, m.p_L)),
                                toArray(X_WO[static_cast<std::size_t>(m.object)] * m.p_O),
                                std::isfinite(force) ? force : 0.0});
      }
    }
    replay.frames.push_back(std::move(frame));
  }

  for (const hil::SupervisorEvent& e : r.events) {
    std::string label = std::string(e.trip ? "trip: " : "") + hil::supervisorCauseName(e.cause);
    if (e.joint >= 0 && static_cast<std::size_t>(e.joint) < r.joint_names.size())
      label += " (" + r.joint_names[static_cast<std::size_t>(e.joint)] + ")";
    replay.events.push_back({e.t_s, label, e.trip});
  }
  replay.caption =
      "Drag to turn, scroll to zoom. Poses from the measured joint angles at " +
      std::to_string(static_cast<int>(std::lround(1.0 / (static_cast<double>(stride) * period_s)))) +
      " frames per second of run time; lines join each adopted minimum's link point to its object point, coloured by "
      "the contact force on its link (green: none, red: the run's largest); a link drawn red touched the scene during "
      "the frame; bars: contact torques (Eq. 1-2) after the fade; marks under the slider: supervisor events (red: "
      "trips).";
  return replay;
}

nlohmann::json replaySummary(const reports::Replay3d& replay, const hil::RunResult& r) {
  nlohmann::json first = nlohmann::json::object();
  for (std::size_t i = 0; i < replay.links.size(); ++i) first[replay.links[i].name] = nullptr;
  for (std::size_t l = 0; l < r.link_names.size() && l < 32; ++l) {
    if (!first.contains(r.link_names[l])) continue;
    for (const hil::TickTelemetry& t : r.telemetry) {
      if (((t.link_penetration_mask >> l) & 1U) != 0) {
        first[r.link_names[l]] = t.t_s;
        break;
      }
    }
  }
  const double span_s = replay.frames.size() > 1 ? replay.frames.back().t_s - replay.frames.front().t_s : 0.0;
  return {{"frames", replay.frames.size()},
          {"frame_rate_hz", span_s > 0.0 ? static_cast<double>(replay.frames.size() - 1) / span_s : 0.0},
          {"first_penetration_s", first}};
}

hil::RunResult runFromLog(const std::filesystem::path& log, const hil::HilSession& session) {
  const hil::TickModel& tick = session.tickModel();
  const arm::ArmModel& model = session.model();
  const double period_s = session.config().control_period_s;
  hil::RunResult r;
  r.options = session.options();
  for (int k = 0; k < tick.device_joints.size(); ++k)
    r.joint_names.push_back(model.joints[static_cast<std::size_t>(tick.device_joints.modelIndex(k))].name);
  for (const arm::Joint& j : model.joints) r.link_names.push_back(j.name);

  std::map<std::int64_t, hil::JointStateRecord> joints;
  std::map<std::int64_t, hil::HapticStatusRecord> statuses;
  hil::MinimaSetAssembler assembler;
  hil::RunLogReader reader(log);
  hil::RunLogEntry entry;
  while (reader.next(entry)) {
    if (const auto* j = std::get_if<fullarm_lcm::joint_state_t>(&entry.message)) {
      joints[j->tick] = hil::fromMessage(*j);
    } else if (const auto* h = std::get_if<fullarm_lcm::haptic_status_t>(&entry.message)) {
      statuses[h->tick] = hil::fromMessage(*h);
    } else if (const auto* m = std::get_if<fullarm_lcm::minima_set_t>(&entry.message)) {
      if (assembler.add(*m)) {
        const hil::MinimaSetRecord& set = assembler.set();
        hil::RecordedSet recorded;
        recorded.id = set.set_id;
        recorded.query_tick = static_cast<std::uint64_t>(std::max<std::int64_t>(0, set.computed_tick));
        recorded.adopted_tick = set.adopted_tick;
        recorded.query_q_rad.assign(set.q_rad.begin(), set.q_rad.begin() + set.num_joints);
        for (int i = 0; i < set.num_minima; ++i)
          recorded.minima.push_back(hil::toLocalMinimum(set.minima[static_cast<std::size_t>(i)]));
        recorded.found = set.num_minima + set.num_minima_dropped;
        r.sets.push_back(std::move(recorded));
      }
    } else if (const auto* e = std::get_if<fullarm_lcm::supervisor_event_t>(&entry.message)) {
      const hil::SupervisorEventRecord record = hil::fromMessage(*e);
      hil::SupervisorEvent event;
      event.tick = static_cast<std::uint64_t>(std::max<std::int64_t>(0, record.tick));
      event.t_s = static_cast<double>(record.tick) * period_s;
      event.cause = static_cast<hil::SupervisorCause>(record.cause_code);
      event.trip = record.severity == hil::EventSeverity::kFault || record.severity == hil::EventSeverity::kEStop;
      event.joint = record.joint;
      event.value = record.value;
      r.events.push_back(event);
    }
  }
  for (const auto& [k, js] : joints) {
    const auto status = statuses.find(k);
    if (status == statuses.end()) continue;
    const hil::HapticStatusRecord& hs = status->second;
    hil::TickTelemetry t;
    t.tick = static_cast<std::uint64_t>(std::max<std::int64_t>(0, k));
    t.t_s = static_cast<double>(k) * period_s;
    t.num_device_joints = js.num_joints;
    t.num_config = hs.num_joints;
    for (int j = 0; j < js.num_joints; ++j) {
      const auto i = static_cast<std::size_t>(j);
      t.q_rad[i] = js.q_rad[i];
      t.tau_load_cell_nm[i] = js.tau_measured_nm[i];
      t.valve_v[i] = js.valve_command_v[i];
    }
    for (int j = 0; j < hs.num_joints; ++j)
      t.tau_contact_nm[static_cast<std::size_t>(j)] = hs.tau_contact_nm[static_cast<std::size_t>(j)];
    for (int l = 0; l < hs.num_links; ++l) {
      const auto i = static_cast<std::size_t>(l);
      t.link_force_W_n[i] = hs.links[i].force_world_n;
      t.link_min_distance_m[i] = hs.links[i].min_distance_m;
      t.link_depth_m[i] = hs.links[i].depth_m;
      if (hs.links[i].in_contact) t.link_contact_mask |= 1U << l;
      if (hs.links[i].penetrating) t.link_penetration_mask |= 1U << l;
    }
    t.tracked_minima = hs.num_minima_tracked;
    t.active_springs = hs.active_springs;
    t.minima_set_id = hs.minima_set_id;
    t.contact_scale = hs.contact_scale;
    r.telemetry.push_back(t);
  }
  return r;
}

}  // namespace fullarm::app
