#pragma once
/// Shared by the run-log tests: a small but complete run log written by RunLogWriter from
/// rings, and the records it was made from.

#include <cmath>
#include <filesystem>
#include <vector>

#include "fullarm/hil/run_log.hpp"

namespace fullarm::hil::test {

/// What went into a sample log.
struct SampleRun {
  fullarm_lcm::run_header_t header{};
  std::vector<JointStateRecord> joints;
  std::vector<HapticStatusRecord> haptics;
  std::vector<MinimaSetRecord> minima;
  std::vector<SupervisorEventRecord> events;
  RunLogStats stats;  ///< the writer's counters after stop()
};

inline JointStateRecord sampleJointState(std::int64_t tick) {
  JointStateRecord r;
  r.utime_us = 1000 * tick;
  r.seq = tick;
  r.tick = tick;
  r.num_joints = 7;
  for (int j = 0; j < 7; ++j) {
    r.q_rad[static_cast<std::size_t>(j)] = std::sin(0.01 * static_cast<double>(tick) + j);
    r.tau_measured_nm[static_cast<std::size_t>(j)] = 10.0 * std::cos(0.02 * static_cast<double>(tick) * j);
    r.valve_command_v[static_cast<std::size_t>(j)] = 0.001 * static_cast<double>((tick * (j + 1)) % 997);
  }
  return r;
}

inline HapticStatusRecord sampleHapticStatus(std::int64_t tick) {
  HapticStatusRecord r;
  r.utime_us = 1000 * tick;
  r.seq = tick;
  r.tick = tick;
  r.active_springs = static_cast<int>(tick % 5);
  r.num_minima_tracked = 20;
  r.minima_set_id = tick / 10;
  r.num_joints = 7;
  r.num_links = 7;
  for (int j = 0; j < 7; ++j)
    r.tau_contact_nm[static_cast<std::size_t>(j)] = 0.5 * j + 1e-3 * static_cast<double>(tick);
  r.links[6].force_world_n = {1.0, 0.0, -static_cast<double>(tick)};
  r.links[6].in_contact = tick % 3 == 0;
  return r;
}

inline MinimaSetRecord sampleMinimaSet(std::int64_t id) {
  MinimaSetRecord s;
  s.utime_us = 10000 * id + 500;
  s.seq = id;
  s.set_id = id;
  s.computed_tick = 10 * id;
  s.computed_utime_us = 10000 * id;
  s.adopted_tick = 10 * id + 2;
  s.num_joints = 7;
  for (int j = 0; j < 7; ++j) s.q_rad[static_cast<std::size_t>(j)] = 0.1 * j;
  s.num_minima = 25;  // three fragments
  for (int i = 0; i < s.num_minima; ++i) {
    MinimumRecord& m = s.minima[static_cast<std::size_t>(i)];
    m.link = i % 7;
    m.object = 1;
    m.tri_link = i;
    m.tri_object = 2 * i;
    m.distance_m = 0.001 * i;
    m.p_link_m = {0.01 * i, 0.0, 0.1};
    m.previous_distance_m = std::nan("");
  }
  return s;
}

/// Writes `ticks` ticks of a run through rings and the writer thread; the header first.
inline SampleRun writeSampleLog(const std::filesystem::path& file, int ticks, int ring_capacity = 4096) {
  SampleRun run;
  run.header.utime = 0;
  run.header.seq = 0;
  run.header.wall_utime = 1700000000000000;
  run.header.fullarm_version = "0.1.0";
  run.header.command_line = "fullarm run --io sim";
  run.header.io = "sim";
  run.header.clock = "lockstep";
  run.header.mode = "full-arm";
  run.header.seed = 7;
  run.header.tick_period_us = 1000;
  run.header.num_files = 1;
  run.header.files.resize(1);
  run.header.files[0].role = "scene";
  run.header.files[0].path = "scenes/valve_wall.yaml";
  run.header.files[0].sha256 = std::string(64, 'a');
  run.header.num_parameters = 1;
  run.header.parameters.resize(1);
  run.header.parameters[0].key = "duration_s";
  run.header.parameters[0].value = "10";

  SpscRing<JointStateRecord> joints(static_cast<std::size_t>(ring_capacity));
  SpscRing<HapticStatusRecord> haptics(static_cast<std::size_t>(ring_capacity));
  SpscRing<MinimaSetRecord> minima(256);  // a set every 10 ticks: room for 2,560 ticks
  SpscRing<SupervisorEventRecord> events(64);
  RunLogWriter writer({file, std::chrono::milliseconds(1), std::chrono::milliseconds(5)});
  writer.writeMessage(channel::kRunHeader, 0, run.header);
  writer.addSource(joints, channel::kJointState);
  writer.addSource(haptics, channel::kHapticStatus);
  writer.addSource(minima, channel::kMinimaSet);
  writer.addSource(events, channel::kSupervisorEvent);
  writer.start();
  for (std::int64_t tick = 0; tick < ticks; ++tick) {
    run.joints.push_back(sampleJointState(tick));
    joints.tryPush(run.joints.back());
    run.haptics.push_back(sampleHapticStatus(tick));
    haptics.tryPush(run.haptics.back());
    if (tick % 10 == 2) {
      run.minima.push_back(sampleMinimaSet(tick / 10));
      minima.tryPush(run.minima.back());
    }
    if (tick == ticks / 2) {
      SupervisorEventRecord e;
      e.utime_us = 1000 * tick;
      e.seq = 0;
      e.tick = tick;
      e.cause_code = 3;
      e.severity = EventSeverity::kFault;
      e.joint = 4;
      e.value = 2.5;
      e.limit = 2.0;
      e.setMessage("joint 4 velocity beyond its limit");
      run.events.push_back(e);
      events.tryPush(e);
    }
  }
  writer.stop();
  run.stats = writer.stats();
  return run;
}

}  // namespace fullarm::hil::test
