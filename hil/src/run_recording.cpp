#include "fullarm/hil/run_recording.hpp"

#include <charconv>
#include <chrono>
#include <cmath>
#include <limits>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "fullarm/core/config_error.hpp"
#include "fullarm/hil/lcm_io.hpp"

namespace fullarm::hil {

namespace {

constexpr std::size_t kTickRingRecords = 16384;  // 16 s of ticks between two drains at most
constexpr std::size_t kSetRingRecords = 256;     // 2.5 s of sets at 100 Hz
constexpr std::size_t kEventRingRecords = 1024;

EventSeverity severityOf(const SupervisorEvent& e) noexcept {
  if (!e.trip) return e.cause == SupervisorCause::kMinimaStale ? EventSeverity::kWarning : EventSeverity::kInfo;
  switch (e.cause) {
    case SupervisorCause::kEstopCommand:
    case SupervisorCause::kEstopSignal:
    case SupervisorCause::kHeartbeatLost:
      return EventSeverity::kEStop;
    default:
      return EventSeverity::kFault;
  }
}

fullarm_lcm::run_file_t fileEntry(const std::string& role, const std::filesystem::path& path) {
  fullarm_lcm::run_file_t f{};
  f.role = role;
  f.path = std::filesystem::absolute(path).string();
  f.sha256 = sha256File(path);
  return f;
}

fullarm_lcm::run_parameter_t parameter(const std::string& key, const std::string& value) {
  fullarm_lcm::run_parameter_t p{};
  p.key = key;
  p.value = value;
  return p;
}

std::string exact(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

const char* modeName(haptics::RenderMode mode) noexcept {
  return mode == haptics::RenderMode::kFullArm ? "full-arm" : "hand-only";
}

}  // namespace

std::uint32_t encodeInputFlags(const RecordedTick& tick, std::uint64_t previous_heartbeat) noexcept {
  std::uint32_t f = tick.sample.out_of_range_mask & kInputFlagOutOfRangeMask;
  if (!tick.device_status.ok()) f |= kInputFlagDeviceFault;
  if ((tick.device_status.faults & kFaultLinkLost) != 0) f |= kInputFlagLinkLost;
  if (tick.requests.estop_command) f |= kInputFlagEstopCommand;
  if (tick.requests.estop_signal) f |= kInputFlagEstopSignal;
  if (tick.requests.reset_command) f |= kInputFlagReset;
  if (tick.requests.overrun_fault) f |= kInputFlagOverrunFault;
  if (tick.requests.heartbeat_enabled) f |= kInputFlagHeartbeatWatched;
  if (tick.requests.heartbeat != previous_heartbeat) f |= kInputFlagHeartbeatBeat;
  if (tick.requests.peer_heartbeat_lost) f |= kInputFlagPeerHeartbeatLost;
  return f;
}

RunRecorder::RunRecorder(const std::filesystem::path& file, bool threaded)
    : joints_(kTickRingRecords),
      valves_(kTickRingRecords),
      haptics_(kTickRingRecords),
      events_(kEventRingRecords),
      sets_(kSetRingRecords),
      threaded_(threaded) {
  RunLogWriterOptions options;
  options.file = file;
  writer_ = std::make_unique<RunLogWriter>(options);
}

void RunRecorder::begin(const HilSession& session, const std::string& command_line) {
  if (begun_) throw std::logic_error("RunRecorder::begin: the header is written once");
  begun_ = true;
  const RunOptions& o = session.options();
  fullarm_lcm::run_header_t h{};
  h.utime = 0;
  h.seq = 0;
  h.wall_utime =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();
  h.fullarm_version = FULLARM_VERSION;
  h.command_line = command_line;
  h.io = ioKindName(o.io);
  h.clock = clockKindName(o.clock);
  h.mode = modeName(o.mode);
  h.seed = static_cast<std::int64_t>(o.seed);
  h.tick_period_us = static_cast<std::int32_t>(std::lround(session.config().control_period_s * 1e6));
  h.files = {fileEntry("arm", o.arm_config),     fileEntry("plant", o.plant_config),
             fileEntry("gains", o.gains_config), fileEntry("haptics", o.haptics_config),
             fileEntry("hil", o.hil_config),     fileEntry("scene", o.scene),
             fileEntry("user", o.user)};
  if (o.io == IoKind::kFakeDaq || o.io == IoKind::kComedi) h.files.push_back(fileEntry("daq", o.daq_config));
  h.num_files = static_cast<std::int16_t>(h.files.size());
  h.parameters = {parameter("duration_s", exact(o.duration_s)), parameter("start_posture", o.start_posture),
                  parameter("global_period_ticks", std::to_string(session.config().global_period_ticks)),
                  parameter("delivery_delay_ticks", std::to_string(session.config().delivery_delay_ticks)),
                  parameter("oracle", o.oracle ? "true" : "false")};
  // A remote plant or I/O node (--io lcm): what it said it serves when configure() accepted it
  // (its plant file is the node's, not the `plant` file above, which gives the tick its joints).
  if (const auto* lcm = dynamic_cast<const LcmIoDevice*>(session.deviceOrNull()); lcm != nullptr) {
    if (const IoNodeInfo* node = lcm->nodeInfo(); node != nullptr) {
      std::string names;
      for (const std::string& n : node->joint_names) names += (names.empty() ? "" : ",") + n;
      h.parameters.push_back(parameter("io_node_joints", names));
      h.parameters.push_back(parameter("io_node_period_us", std::to_string(node->period_us)));
      h.parameters.push_back(parameter("io_node_simulated", node->simulated ? "true" : "false"));
      h.parameters.push_back(parameter("io_node_scripted_user", node->scripted_user ? "true" : "false"));
      h.parameters.push_back(parameter("io_node_plant", node->plant));
    }
  }
  h.num_parameters = static_cast<std::int16_t>(h.parameters.size());
  writer_->writeMessage(channel::kRunHeader, 0, h);
  writer_->addSource(joints_, channel::kJointState);
  writer_->addSource(valves_, channel::kValveCommand);
  writer_->addSource(haptics_, channel::kHapticStatus);
  writer_->addSource(events_, channel::kSupervisorEvent);
  writer_->addSource(sets_, channel::kMinimaSet);
  if (threaded_) writer_->start();
}

RunRecorder::~RunRecorder() {
  if (!finished_) (void)finish();
}

void RunRecorder::recordTick(const RecordedTick& inputs, const TickTelemetry& t, const IoVector& written,
                             bool safe_output, std::int64_t utime_us) noexcept {
  const std::int64_t tick = static_cast<std::int64_t>(t.tick);
  const std::uint32_t flags = encodeInputFlags(inputs, previous_heartbeat_);
  previous_heartbeat_ = inputs.requests.heartbeat;
  joints_.tryPushWith([&](JointStateRecord& r) {
    r.utime_us = utime_us;
    r.seq = seq_joints_;
    r.tick = tick;
    r.num_joints = t.num_device_joints;
    for (int k = 0; k < t.num_device_joints; ++k) {
      const std::size_t i = static_cast<std::size_t>(k);
      r.q_rad[i] = k < inputs.sample.q_rad.size() ? inputs.sample.q_rad[k] : std::numeric_limits<double>::quiet_NaN();
      r.tau_measured_nm[i] = k < inputs.sample.tau_load_cell_nm.size() ? inputs.sample.tau_load_cell_nm[k]
                                                                       : std::numeric_limits<double>::quiet_NaN();
      r.valve_command_v[i] = t.valve_v[i];
    }
    r.input_flags = flags;
  });
  ++seq_joints_;
  valves_.tryPushWith([&](ValveCommandRecord& r) {
    r.utime_us = utime_us;
    r.seq = seq_valves_;
    r.tick = tick;
    r.num_valves = static_cast<int>(written.size());
    for (int k = 0; k < written.size(); ++k) r.valve_command_v[static_cast<std::size_t>(k)] = written[k];
    r.safe_output = safe_output;
  });
  ++seq_valves_;
  haptics_.tryPushWith([&](HapticStatusRecord& r) {
    r.utime_us = utime_us;
    r.seq = seq_haptics_;
    r.tick = tick;
    r.mode = LoggedMode::kFullArm;
    r.active_springs = t.active_springs;
    r.num_minima_tracked = t.tracked_minima;
    r.minima_set_id = t.minima_set_id;
    r.contact_scale = t.contact_scale;
    r.num_joints = t.num_config;
    r.num_links = t.num_config;
    for (int l = 0; l < t.num_config; ++l) {
      const std::size_t i = static_cast<std::size_t>(l);
      r.tau_contact_nm[i] = t.tau_contact_nm[i];
      LinkContactStatus& link = r.links[i];
      link.force_world_n = t.link_force_W_n[i];
      link.min_distance_m = t.link_min_distance_m[i];
      link.depth_m = t.link_depth_m[i];
      link.in_contact = ((t.link_contact_mask >> l) & 1u) != 0;
      link.penetrating = ((t.link_penetration_mask >> l) & 1u) != 0;
      link.contact_duration_s = t.link_contact_s[i];
      link.total_penetration_s = t.link_penetration_s[i];
    }
  });
  ++seq_haptics_;
  for (int e = 0; e < t.num_events; ++e) {
    const SupervisorEvent& ev = t.events[static_cast<std::size_t>(e)];
    events_.tryPushWith([&](SupervisorEventRecord& r) {
      r.utime_us = static_cast<std::int64_t>(std::llround(ev.t_s * 1e6));
      r.seq = seq_events_;
      r.tick = static_cast<std::int64_t>(ev.tick);
      r.cause_code = static_cast<int>(ev.cause);
      r.severity = severityOf(ev);
      r.joint = ev.joint;
      r.value = ev.value;
      r.limit = std::numeric_limits<double>::quiet_NaN();
      r.setMessage(supervisorCauseName(ev.cause));
    });
    ++seq_events_;
  }
}

void RunRecorder::recordAdoptedSet(const MinimaSetRecord& set) noexcept {
  sets_.tryPushWith([&](MinimaSetRecord& r) {
    r = set;
    r.seq = seq_sets_;
  });
  ++seq_sets_;
}

void RunRecorder::pump() {
  if (!threaded_) (void)writer_->drainOnce();
}

RunLogStats RunRecorder::finish() {
  finished_ = true;
  writer_->stop();
  return writer_->stats();
}

void toSetRecord(const RecordedSet& set, double period_s, MinimaSetRecord& record) noexcept {
  record.utime_us = static_cast<std::int64_t>(std::llround(static_cast<double>(set.adopted_tick) * period_s * 1e6));
  record.set_id = set.id;
  record.computed_tick = static_cast<std::int64_t>(set.query_tick);
  record.computed_utime_us =
      static_cast<std::int64_t>(std::llround(static_cast<double>(set.query_tick) * period_s * 1e6));
  record.adopted_tick = set.adopted_tick;
  record.num_joints = static_cast<int>(std::min<std::size_t>(set.query_q_rad.size(), kMaxRecordJoints));
  for (int j = 0; j < record.num_joints; ++j)
    record.q_rad[static_cast<std::size_t>(j)] = set.query_q_rad[static_cast<std::size_t>(j)];
  fillMinima(set.minima, record);
  record.num_minima_dropped += set.found - static_cast<int>(set.minima.size());
}

// --- replay ----------------------------------------------------------------------------------

namespace {

struct LoggedTick {
  fullarm_lcm::joint_state_t joints{};
  bool have_haptics = false;
  fullarm_lcm::haptic_status_t haptics{};
};

/// A header parameter's value as a finite duration > 0 in seconds: the whole text, as written by
/// exact(); anything else is an error naming the log and the parameter.
double headerSeconds(const fullarm_lcm::run_parameter_t& p, const std::filesystem::path& log) {
  double v = 0.0;
  const char* first = p.value.data();
  const char* last = first + p.value.size();
  const auto [end, ec] = std::from_chars(first, last, v);
  if (p.value.empty() || ec != std::errc() || end != last || !std::isfinite(v) || v <= 0.0) {
    throw core::ConfigError(log, "run header parameter " + p.key,
                            "expected a finite number of seconds > 0, got '" + p.value + "'");
  }
  return v;
}

/// A header parameter's value as a whole number of ticks >= `min`, else an error naming the log
/// and the parameter.
int headerTicks(const fullarm_lcm::run_parameter_t& p, const std::filesystem::path& log, int min) {
  int v = 0;
  const char* first = p.value.data();
  const char* last = first + p.value.size();
  const auto [end, ec] = std::from_chars(first, last, v);
  if (p.value.empty() || ec != std::errc() || end != last || v < min) {
    throw core::ConfigError(log, "run header parameter " + p.key,
                            "expected a whole number of ticks >= " + std::to_string(min) + ", got '" + p.value + "'");
  }
  return v;
}

RunOptions optionsFromHeader(const fullarm_lcm::run_header_t& h, const std::filesystem::path& log) {
  RunOptions o;
  if (h.io == "sim") {
    o.io = IoKind::kSim;
  } else if (h.io == "fakedaq") {
    o.io = IoKind::kFakeDaq;
  } else if (h.io == "comedi") {
    o.io = IoKind::kComedi;
  } else if (h.io == "lcm") {
    o.io = IoKind::kLcm;
  } else {
    throw core::ConfigError(log, "run header io", "unknown I/O back-end '" + h.io + "'");
  }
  o.clock = h.clock == "realtime" ? ClockKind::kRealtime : ClockKind::kLockstep;
  o.mode = h.mode == "hand-only" ? haptics::RenderMode::kHandOnly : haptics::RenderMode::kFullArm;
  o.seed = static_cast<std::uint64_t>(h.seed);
  for (const fullarm_lcm::run_file_t& f : h.files) {
    if (f.role == "arm") o.arm_config = f.path;
    if (f.role == "plant") o.plant_config = f.path;
    if (f.role == "gains") o.gains_config = f.path;
    if (f.role == "haptics") o.haptics_config = f.path;
    if (f.role == "hil") o.hil_config = f.path;
    if (f.role == "scene") o.scene = f.path;
    if (f.role == "user") o.user = f.path;
    if (f.role == "daq") o.daq_config = f.path;
  }
  for (const fullarm_lcm::run_parameter_t& p : h.parameters) {
    if (p.key == "duration_s") o.duration_s = headerSeconds(p, log);
    if (p.key == "start_posture") o.start_posture = p.value;
    if (p.key == "global_period_ticks") o.global_period_ticks = headerTicks(p, log, 1);
    if (p.key == "delivery_delay_ticks") o.delivery_delay_ticks = headerTicks(p, log, 1);
  }
  o.oracle = false;
  return o;
}

}  // namespace

ReplayReport replayLog(const std::filesystem::path& log) {
  ReplayReport report;
  report.log = log;
  RunLogReader reader(log);
  RunLogEntry entry;
  bool have_header = false;
  fullarm_lcm::run_header_t header{};
  std::vector<LoggedTick> ticks;
  // The writer drains its rings one after the other while the tick runs on: a tick's haptic
  // status may precede its joint state in the log. They are joined by tick once all is read.
  std::map<std::int64_t, fullarm_lcm::haptic_status_t> statuses;
  std::map<std::int64_t, MinimaSetRecord> adopted;  // by adopted tick
  auto assembler = std::make_unique<MinimaSetAssembler>();
  while (reader.next(entry)) {
    if (const auto* h = std::get_if<fullarm_lcm::run_header_t>(&entry.message)) {
      header = *h;
      have_header = true;
    } else if (const auto* j = std::get_if<fullarm_lcm::joint_state_t>(&entry.message)) {
      ticks.push_back({*j, false, {}});
    } else if (const auto* s = std::get_if<fullarm_lcm::haptic_status_t>(&entry.message)) {
      statuses[s->tick] = *s;
    } else if (const auto* m = std::get_if<fullarm_lcm::minima_set_t>(&entry.message)) {
      if (assembler->add(*m) && assembler->set().adopted_tick >= 0) {
        adopted[assembler->set().adopted_tick] = assembler->set();
      }
    }
  }
  for (LoggedTick& lt : ticks) {
    if (const auto it = statuses.find(lt.joints.tick); it != statuses.end()) {
      lt.haptics = it->second;
      lt.have_haptics = true;
    }
  }
  report.truncated = reader.truncated();
  report.warning = reader.warning();
  if (!have_header) throw RunLogError(log.string() + ": no run header: not a fullarm run log");
  report.options = optionsFromHeader(header, log);
  for (const fullarm_lcm::run_parameter_t& p : header.parameters) {
    static constexpr std::string_view kNode = "io_node_";
    if (p.key.compare(0, kNode.size(), kNode) == 0) report.io_node.emplace_back(p.key.substr(kNode.size()), p.value);
  }
  report.clock = header.clock;
  for (const fullarm_lcm::run_file_t& f : header.files) {
    std::string now;
    try {
      now = sha256File(f.path);
    } catch (const std::exception&) {
      now = "unreadable";
    }
    if (now != f.sha256) report.changed_files.push_back(f.role + " (" + f.path + ")");
  }

  const HilSession session(report.options, false);
  const TickModel& model = session.tickModel();
  TickData data(model);
  IoVector valve;
  TickTelemetry t;
  std::uint64_t heartbeat = 0;
  std::vector<haptics::LocalMinimum> minima;
  std::vector<double> query_q;
  for (const LoggedTick& lt : ticks) {
    // A truncated log may end between a tick's joint state and its haptic status.
    if (!lt.have_haptics) break;
    const fullarm_lcm::joint_state_t& js = lt.joints;
    const std::uint32_t flags = static_cast<std::uint32_t>(js.input_flags);
    JointSample sample;
    sample.q_rad = Eigen::Map<const IoVector>(js.q_rad.data(), js.num_joints);
    sample.tau_load_cell_nm = Eigen::Map<const IoVector>(js.tau_measured_nm.data(), js.num_joints);
    sample.out_of_range_mask = flags & kInputFlagOutOfRangeMask;
    sample.t_s = static_cast<double>(js.utime) * 1e-6;
    TickInputs in;
    in.sample = &sample;
    if ((flags & kInputFlagDeviceFault) != 0) {
      const std::uint32_t link = (flags & kInputFlagLinkLost) != 0 ? kFaultLinkLost : 0u;
      in.device_status = core::RtStatus::fault(core::RtCode::kBadInput, kFaultDeviceRead | link, "device read failed");
    }
    in.requests.estop_command = (flags & kInputFlagEstopCommand) != 0;
    in.requests.estop_signal = (flags & kInputFlagEstopSignal) != 0;
    in.requests.reset_command = (flags & kInputFlagReset) != 0;
    in.requests.overrun_fault = (flags & kInputFlagOverrunFault) != 0;
    in.requests.heartbeat_enabled = (flags & kInputFlagHeartbeatWatched) != 0;
    if ((flags & kInputFlagHeartbeatBeat) != 0) ++heartbeat;
    in.requests.heartbeat = heartbeat;
    in.requests.peer_heartbeat_lost = (flags & kInputFlagPeerHeartbeatLost) != 0;
    MinimaDelivery delivery;
    if (const auto it = adopted.find(js.tick); it != adopted.end()) {
      const MinimaSetRecord& set = it->second;
      minima.clear();
      for (int i = 0; i < set.num_minima; ++i)
        minima.push_back(toLocalMinimum(set.minima[static_cast<std::size_t>(i)]));
      query_q.assign(set.q_rad.begin(), set.q_rad.begin() + set.num_joints);
      delivery.set_id = set.set_id;
      delivery.minima = minima;
      delivery.query_q_rad = query_q;
      in.minima = &delivery;
      ++report.sets;
    }
    stepTick(model, data, in, valve, t);
    ++report.ticks;
    const auto note = [&](const std::string& what) {
      if (report.first_mismatch.empty()) report.first_mismatch = "tick " + std::to_string(js.tick) + ": " + what;
    };
    for (int k = 0; k < js.num_joints; ++k) {
      if (js.valve_command_v[static_cast<std::size_t>(k)] != t.valve_v[static_cast<std::size_t>(k)]) {
        ++report.valve_mismatches;
        note("valve " + std::to_string(k));
        break;
      }
    }
    const fullarm_lcm::haptic_status_t& hs = lt.haptics;
    for (int l = 0; l < hs.num_joints && l < t.num_config; ++l) {
      if (hs.tau_contact_nm[static_cast<std::size_t>(l)] != t.tau_contact_nm[static_cast<std::size_t>(l)]) {
        ++report.torque_mismatches;
        note("contact torque " + std::to_string(l));
        break;
      }
    }
    for (int l = 0; l < hs.num_links && l < t.num_config; ++l) {
      const auto& f = hs.links[static_cast<std::size_t>(l)].force_world_n;
      const auto& g = t.link_force_W_n[static_cast<std::size_t>(l)];
      if (f[0] != g[0] || f[1] != g[1] || f[2] != g[2]) {
        ++report.force_mismatches;
        note("force on link " + std::to_string(l));
        break;
      }
    }
  }
  return report;
}

}  // namespace fullarm::hil
