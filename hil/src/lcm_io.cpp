#include "fullarm/hil/lcm_io.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <exception>
#include <stdexcept>
#include <string_view>

#include "lcm_node.hpp"
#include "lcm_walk.hpp"

namespace fullarm::hil {

using detail::Clock;
using detail::seconds;

namespace {

std::int64_t wallMicros() {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// The checks shared by the io decoders: hash, length, no byte left over.
template <class Message>
DecodeStatus decodeIo(std::span<const std::uint8_t> bytes, Message& m) noexcept {
  if (bytes.size() > static_cast<std::size_t>(INT_MAX)) return DecodeStatus::kMalformed;
  if (bytes.size() < 8) return DecodeStatus::kTruncated;
  std::uint64_t h = 0;
  for (std::size_t i = 0; i < 8; ++i) h = (h << 8) | bytes[i];
  if (static_cast<std::int64_t>(h) != Message::getHash()) return DecodeStatus::kWrongHash;
  try {
    const int used = m.decode(bytes.data(), 0, static_cast<int>(bytes.size()));
    if (used < 0) return DecodeStatus::kTruncated;
    if (used != static_cast<int>(bytes.size())) return DecodeStatus::kMalformed;
  } catch (const std::exception&) {
    return DecodeStatus::kMalformed;  // a negative count: the generated decoder's resize throws
  }
  return DecodeStatus::kOk;
}

/// The layout of an io_node_info_t, walked before the generated decoder reads its strings:
/// utime, seq; num_joints and the joint names; period_us, simulated, scripted_user; plant.
DecodeStatus checkNodeInfoLayout(std::span<const std::uint8_t> bytes) noexcept {
  detail::LcmWalk w(bytes);
  w.skip(16);
  w.strings(w.count(1, kMaxIoJoints), 1, kMaxNodeJointNameChars);
  w.skip(6);
  w.string(0, kMaxNodePlantChars);
  return w.finish();
}

// Printable ASCII only: no control characters (C0, DEL, C1) and no bytes of other encodings,
// which would reach error messages and terminal logs as they are.
bool printable(const std::string& text) noexcept {
  return std::all_of(text.begin(), text.end(), [](char c) {
    const auto b = static_cast<unsigned char>(c);
    return b >= 0x20 && b <= 0x7E;
  });
}

}  // namespace

fullarm_lcm::io_node_info_t toMessage(const IoNodeInfo& info) {
  fullarm_lcm::io_node_info_t m{};
  m.num_joints = static_cast<std::int8_t>(info.joint_names.size());
  m.joint_names = info.joint_names;
  m.period_us = info.period_us;
  m.simulated = info.simulated ? 1 : 0;
  m.scripted_user = info.scripted_user ? 1 : 0;
  m.plant = info.plant;
  return m;
}

IoNodeInfo fromMessage(const fullarm_lcm::io_node_info_t& m) {
  IoNodeInfo info;
  info.joint_names = m.joint_names;
  info.period_us = m.period_us;
  info.simulated = m.simulated != 0;
  info.scripted_user = m.scripted_user != 0;
  info.plant = m.plant;
  return info;
}

std::string describeJointsAndPeriod(const std::vector<std::string>& joint_names, std::int32_t period_us) {
  std::string text;
  for (const std::string& name : joint_names) text += (text.empty() ? "" : ",") + name;
  if (joint_names.empty()) text = "no joints";
  return text + " every " + std::to_string(period_us) + " us";
}

DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::io_command_t& out) noexcept {
  const DecodeStatus s = decodeIo(bytes, out);
  if (s != DecodeStatus::kOk) return s;
  if (out.num_valves < 0 || out.num_valves > kMaxIoJoints) return DecodeStatus::kMalformed;
  if (out.valve_command_v.size() != static_cast<std::size_t>(out.num_valves)) return DecodeStatus::kMalformed;
  return DecodeStatus::kOk;
}

DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::io_reading_t& out) noexcept {
  const DecodeStatus s = decodeIo(bytes, out);
  if (s != DecodeStatus::kOk) return s;
  const auto n = static_cast<std::size_t>(out.num_joints);
  if (out.num_joints < 0 || out.num_joints > kMaxIoJoints || out.q_rad.size() != n ||
      out.tau_load_cell_nm.size() != n || out.p_a_pa.size() != n || out.p_b_pa.size() != n) {
    return DecodeStatus::kMalformed;
  }
  // Flag bits only for joints the reading has.
  if ((static_cast<std::uint32_t>(out.pressure_mask) >> out.num_joints) != 0 ||
      (static_cast<std::uint32_t>(out.out_of_range_mask) >> out.num_joints) != 0) {
    return DecodeStatus::kMalformed;
  }
  if (out.status_code < 0 || out.status_code > static_cast<int>(core::RtCode::kSolverFailure))
    return DecodeStatus::kMalformed;
  return DecodeStatus::kOk;
}

DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::io_node_info_t& out) noexcept {
  if (bytes.size() > static_cast<std::size_t>(INT_MAX)) return DecodeStatus::kMalformed;
  if (bytes.size() < 8) return DecodeStatus::kTruncated;
  std::uint64_t h = 0;
  for (std::size_t i = 0; i < 8; ++i) h = (h << 8) | bytes[i];
  if (static_cast<std::int64_t>(h) != fullarm_lcm::io_node_info_t::getHash()) return DecodeStatus::kWrongHash;
  // The generated decoder trusts each string's length (a length of 0 or less would be read as
  // a huge one): the layout is checked first.
  const DecodeStatus layout = checkNodeInfoLayout(bytes);
  if (layout != DecodeStatus::kOk) return layout;
  const DecodeStatus s = decodeIo(bytes, out);
  if (s != DecodeStatus::kOk) return s;
  if (out.num_joints < 0 || out.num_joints > kMaxIoJoints ||
      out.joint_names.size() != static_cast<std::size_t>(out.num_joints)) {
    return DecodeStatus::kMalformed;
  }
  if (!std::all_of(out.joint_names.begin(), out.joint_names.end(), printable) || !printable(out.plant)) {
    return DecodeStatus::kMalformed;
  }
  if (out.period_us <= 0 || out.period_us > kMaxNodePeriodUs) return DecodeStatus::kMalformed;
  return DecodeStatus::kOk;
}

// --- the lcm back-end --------------------------------------------------------------------------

/// Receives the node's readings and heartbeats for an LcmIoDevice.
struct LcmIoDevice::Handler {
  fullarm_lcm::io_reading_t reading{};
  bool have_reading = false;  ///< `reading` answers the current command
  std::int64_t want_seq = 0;
  std::uint64_t heartbeats = 0;
  fullarm_lcm::io_node_info_t info{};
  bool have_info = false;  ///< `info` holds the node's description
  LcmIoCounters* counters = nullptr;

  void onMessage(std::span<const std::uint8_t> bytes, const char* channel) {
    if (std::string_view(channel) == channel::kHeartbeat) {
      onHeartbeat(bytes);
    } else if (std::string_view(channel) == channel::kIoNodeInfo) {
      onInfo(bytes);
    } else {
      onReading(bytes);
    }
  }
  void onInfo(std::span<const std::uint8_t> bytes) {
    fullarm_lcm::io_node_info_t m{};
    if (decodeChecked(bytes, m) != DecodeStatus::kOk) {
      ++counters->rejected;
      return;
    }
    info = std::move(m);
    have_info = true;
  }
  void onReading(std::span<const std::uint8_t> bytes) {
    fullarm_lcm::io_reading_t m{};
    if (decodeChecked(bytes, m) != DecodeStatus::kOk) {
      ++counters->rejected;
      return;
    }
    if (m.seq != want_seq || have_reading) {
      ++counters->stale;
      return;
    }
    reading = std::move(m);
    have_reading = true;
  }
  void onHeartbeat(std::span<const std::uint8_t> bytes) {
    HeartbeatRecord h;
    if (decodeChecked(bytes, h) != DecodeStatus::kOk) {
      ++counters->rejected;
      return;
    }
    if (h.node == NodeKind::kPlant) ++heartbeats;
  }
};

LcmIoDevice::LcmIoDevice(arm::JointSelection joints, double period_s, const IoSafetyParams& safety,
                         LcmIoOptions options)
    : IoDevice(std::move(joints), period_s, safety), options_(std::move(options)) {
  if (static_cast<int>(options_.joint_names.size()) != numJoints()) {
    throw std::invalid_argument("lcm I/O: " + std::to_string(options_.joint_names.size()) + " joint names for " +
                                std::to_string(numJoints()) + " joints");
  }
  held_v_ = IoVector::Zero(numJoints());
}

std::int64_t descriptionId(const IoNodeInfo& info) {
  fullarm_lcm::io_node_info_t m = toMessage(info);
  m.utime = 0;
  m.seq = 0;
  std::vector<std::uint8_t> bytes;
  encodeMessage(m, bytes);
  std::uint64_t h = 14695981039346656037ULL;  // FNV-1a, 64 bits
  for (const std::uint8_t b : bytes) {
    h ^= b;
    h *= 1099511628211ULL;
  }
  return h == 0 ? 1 : static_cast<std::int64_t>(h);
}

LcmIoDevice::~LcmIoDevice() = default;

void LcmIoDevice::onConfigure() {
  have_info_ = false;  // a failed configure keeps no earlier node's description
  description_id_ = 0;
  lcm_ = std::make_unique<lcm::LCM>(options_.url);
  if (!lcm_->good()) throw DeviceError("lcm I/O: cannot open the LCM URL " + options_.url);
  handler_ = std::make_unique<Handler>();
  handler_->counters = &counters_;
  // Subscriptions end with the LCM instance (lcm_destroy).
  lcm_subscription_t* r = detail::subscribeRaw(*lcm_, channel::kIoReading, handler_.get(), 64);
  lcm_subscription_t* h = detail::subscribeRaw(*lcm_, channel::kHeartbeat, handler_.get(), 64);
  lcm_subscription_t* d = detail::subscribeRaw(*lcm_, channel::kIoNodeInfo, handler_.get(), 8);
  if (r == nullptr || h == nullptr || d == nullptr) throw DeviceError("lcm I/O: cannot subscribe on " + options_.url);
  const auto deadline = detail::after(options_.connect_timeout_s);
  while ((handler_->heartbeats == 0 || !handler_->have_info) && Clock::now() < deadline) {
    lcm_->handleTimeout(detail::millisUntil(deadline) + 1);
  }
  // The description is read here only: the reads do not decode it.
  lcm_unsubscribe(lcm_->getUnderlyingLCM(), d);
  if (handler_->heartbeats == 0) {
    throw DeviceError("lcm I/O: no plant node answered on " + options_.url + " within " +
                      detail::seconds(options_.connect_timeout_s) +
                      " (start `fullarm plant serve` with the same --lcm-url)");
  }
  if (!handler_->have_info) {
    throw DeviceError("lcm I/O: the node at " + options_.url + " did not say what it serves within " +
                      detail::seconds(options_.connect_timeout_s) + " (io_node_info_t on " + channel::kIoNodeInfo +
                      (counters_.rejected > 0
                           ? "; " + std::to_string(counters_.rejected) + " malformed messages were dropped"
                           : std::string()) +
                      "): start it with a `fullarm plant serve` of this version");
  }
  const IoNodeInfo info = fromMessage(handler_->info);
  const auto period_us = static_cast<std::int32_t>(std::lround(period() * 1e6));
  if (info.joint_names != options_.joint_names || info.period_us != period_us) {
    throw DeviceError("lcm I/O: the node at " + options_.url + " serves joints " +
                      describeJointsAndPeriod(info.joint_names, info.period_us) + "; expected " +
                      describeJointsAndPeriod(options_.joint_names, period_us) +
                      " (start `fullarm plant serve` with the same plant file and loop configuration)");
  }
  info_ = info;
  have_info_ = true;
  description_id_ = descriptionId(info);
  held_v_.setZero();
  held_enable_ = false;
  seq_ = 0;
  lost_ = false;
  have_sample_ = false;
  counters_.consecutive_missed = 0;
}

core::RtStatus LcmIoDevice::onRead(JointSample& sample) noexcept {
  if (!lcm_) return core::RtStatus::fault(core::RtCode::kNotConfigured, kFaultDeviceRead, "lcm I/O: not connected");
  try {
    if (!publishHeld()) {
      return core::RtStatus::fault(core::RtCode::kBadState, kFaultDeviceRead, "lcm I/O: the command could not be sent");
    }
    handler_->want_seq = seq_;  // replies are taken only by the handle calls below
    handler_->have_reading = false;
    // Once a reply failed to come, later reads only take what has already arrived when the
    // timeout is longer than a period (lockstep): a lost node must not stall every later tick by
    // the whole timeout. A timeout within the period (real time) is always waited for.
    const bool poll_only = lost_ && options_.reply_timeout_s > period();
    const double wait_s = poll_only ? 0.0 : options_.reply_timeout_s;
    const auto deadline = detail::after(wait_s);
    if (poll_only) {
      while (!handler_->have_reading && lcm_->handleTimeout(0) > 0) {
      }
    }
    while (!handler_->have_reading && Clock::now() < deadline) {
      (void)detail::handleWithin(*lcm_, std::chrono::duration<double>(deadline - Clock::now()).count());
    }
    if (!handler_->have_reading) {
      lost_ = true;
      ++counters_.timeouts;
      if (++counters_.consecutive_missed >= options_.max_missed_replies || !have_sample_) {
        // Replies that arrived but did not decode: most likely a node of another version (the
        // message's type hash differs), not a lost link.
        return core::RtStatus::fault(core::RtCode::kBadState, kFaultDeviceRead | kFaultLinkLost,
                                     counters_.rejected > 0
                                         ? "lcm I/O: no reading from the I/O node in time; readings that arrived were "
                                           "rejected as damaged or of another message version (is the node a "
                                           "`fullarm plant serve` of this version?)"
                                         : "lcm I/O: no reading from the I/O node in time (communication lost)");
      }
      sample = last_sample_;  // a held reading, as a late DAQ conversion would give
      return {};
    }
  } catch (const std::exception&) {
    return core::RtStatus::fault(core::RtCode::kBadState, kFaultDeviceRead, "lcm I/O: receive failed");
  }
  lost_ = false;
  counters_.consecutive_missed = 0;
  const fullarm_lcm::io_reading_t& m = handler_->reading;
  if (m.num_joints != numJoints()) {
    return core::RtStatus::fault(core::RtCode::kBadInput, kFaultDeviceRead,
                                 "lcm I/O: the node serves another number of joints");
  }
  if (m.description_id != description_id_) {
    return core::RtStatus::fault(core::RtCode::kBadInput, kFaultDeviceRead,
                                 "lcm I/O: the node now serves under another description (restarted with other files "
                                 "or user?): configure the device again");
  }
  ++counters_.readings;
  const int n = numJoints();
  sample.q_rad.resize(n);
  sample.tau_load_cell_nm.resize(n);
  sample.p_a_pa.setZero(n);
  sample.p_b_pa.setZero(n);
  sample.pressure_mask = static_cast<std::uint32_t>(m.pressure_mask);
  for (int k = 0; k < n; ++k) {
    const auto i = static_cast<std::size_t>(k);
    sample.q_rad[k] = m.q_rad[i];
    sample.tau_load_cell_nm[k] = m.tau_load_cell_nm[i];
    if ((sample.pressure_mask >> k) & 1u) {
      sample.p_a_pa[k] = m.p_a_pa[i];
      sample.p_b_pa[k] = m.p_b_pa[i];
    }
  }
  sample.t_s = m.t_s;
  sample.out_of_range_mask = static_cast<std::uint32_t>(m.out_of_range_mask);
  last_sample_ = sample;
  have_sample_ = true;
  if (m.status_code != 0) {
    return core::RtStatus::fault(static_cast<core::RtCode>(m.status_code), static_cast<std::uint32_t>(m.status_faults),
                                 "lcm I/O: the node's read failed");
  }
  return {};
}

bool LcmIoDevice::publishHeld() {
  fullarm_lcm::io_command_t c{};
  c.utime = wallMicros();
  c.seq = ++seq_;
  c.num_valves = static_cast<std::int8_t>(held_v_.size());
  c.valve_command_v.assign(held_v_.data(), held_v_.data() + held_v_.size());
  c.enable = held_enable_ ? 1 : 0;
  encodeMessage(c, buffer_);
  if (lcm_->publish(channel::kIoCommand, buffer_.data(), static_cast<unsigned int>(buffer_.size())) != 0) return false;
  ++counters_.commands;
  return true;
}

void LcmIoDevice::onDeactivate() noexcept {
  held_v_.setZero();
  held_enable_ = false;
  if (!lcm_) return;
  try {
    (void)publishHeld();
  } catch (const std::exception&) {
    // Not sent: the node's watchdog puts out the safe output when commands stop.
  }
}

core::RtStatus LcmIoDevice::onWrite(const IoVector& valve_v, bool toggle_enable) noexcept {
  // Held until the next read carries it to the node, as a DAC holds its output.
  for (int k = 0; k < held_v_.size(); ++k) held_v_[k] = toggle_enable ? valve_v[k] : 0.0;
  held_enable_ = toggle_enable;
  return {};
}

// --- the plant node ----------------------------------------------------------------------------

LcmPlantNode::LcmPlantNode(IoDevice& device, PlantNodeOptions options)
    : device_(device), options_(std::move(options)) {}

PlantNodeResult LcmPlantNode::serve(const std::function<bool()>& stop) {
  PlantNodeResult result;
  detail::NodeLcm node("plant node", options_.url, result.log, options_.on_log);
  lcm::LCM& rx = node.rx;
  lcm::LCM& tx = node.tx;
  const auto log = [&node](const std::string& what) { node.log(what); };

  IoNodeInfo info = options_.info;
  const auto device_period_us = static_cast<std::int32_t>(std::lround(device_.period() * 1e6));
  if (info.period_us == 0) info.period_us = device_period_us;
  if (static_cast<int>(info.joint_names.size()) != device_.numJoints() || info.period_us != device_period_us) {
    throw std::invalid_argument("plant node: the description names " +
                                describeJointsAndPeriod(info.joint_names, info.period_us) + " for a device of " +
                                std::to_string(device_.numJoints()) + " joints every " +
                                std::to_string(device_period_us) + " us");
  }
  fullarm_lcm::io_node_info_t info_message = toMessage(info);
  const std::int64_t description_id = descriptionId(info);
  std::vector<std::uint8_t> info_buffer;
  {
    // What the tick side's decoder would drop is refused here, naming the bounds.
    encodeMessage(info_message, info_buffer);
    fullarm_lcm::io_node_info_t decoded{};
    if (decodeChecked(info_buffer, decoded) != DecodeStatus::kOk) {
      throw std::invalid_argument(
          "plant node: the description (" + describeJointsAndPeriod(info.joint_names, info.period_us) +
          ") is outside what the protocol carries: joint names of 1 to " + std::to_string(kMaxNodeJointNameChars) +
          " printable ASCII characters, at most " + std::to_string(kMaxIoJoints) + " joints, a period up to " +
          std::to_string(kMaxNodePeriodUs) + " us, a plant field of at most " + std::to_string(kMaxNodePlantChars) +
          " characters");
    }
  }
  // At the heartbeat period (the default one when the node sends no heartbeats).
  const auto info_period = std::chrono::duration<double>(
      options_.heartbeat_period_s > 0.0 ? options_.heartbeat_period_s : PlantNodeOptions{}.heartbeat_period_s);
  auto last_info = Clock::now();
  const auto publishInfo = [&] {
    info_message.utime = wallMicros();
    ++info_message.seq;
    encodeMessage(info_message, info_buffer);
    if (tx.publish(channel::kIoNodeInfo, info_buffer.data(), static_cast<unsigned int>(info_buffer.size())) != 0) {
      log("the description could not be sent");
    }
    last_info = Clock::now();
  };

  device_.configure();  // safe outputs
  bool safe = true;
  std::int64_t last_seq = 0;
  SequenceTracker command_seq(1);  ///< the device counts its reads from 1: a new run is heard at once
  auto last_command = Clock::now();
  bool commanded = false;

  fullarm_lcm::io_command_t command{};
  bool have_command = false;
  struct Sink {
    fullarm_lcm::io_command_t* command;
    bool* have;
    std::uint64_t* rejected;
    void onMessage(std::span<const std::uint8_t> bytes, const char* /*channel*/) {
      if (decodeChecked(bytes, *command) != DecodeStatus::kOk) {
        ++*rejected;
        *have = false;
        return;
      }
      *have = true;
    }
  } sink{&command, &have_command, &result.rejected};
  node.subscribe(channel::kIoCommand, &sink, 64);

  LcmPublisherOptions beat;
  beat.node = NodeKind::kPlant;
  beat.heartbeat_period_s = options_.heartbeat_period_s;
  LcmPublisher publisher(tx, beat);
  publisher.setNodeState(-1, true);
  log("serving " + describeJointsAndPeriod(info.joint_names, info.period_us) + " on " + options_.url + " (" +
      (info.simulated ? "simulated" : "real arm") +
      (info.scripted_user ? ", a scripted user strapped in" : ", no user") +
      (info.plant.empty() ? "" : ", plant " + info.plant) + ")");
  publishInfo();

  JointSample sample;
  IoVector valve = IoVector::Zero(device_.numJoints());
  const IoVector zero = IoVector::Zero(device_.numJoints());
  std::vector<std::uint8_t> buffer;
  const auto watchdog = std::chrono::duration<double>(options_.watchdog_timeout_s);
  const auto idle = std::chrono::duration<double>(options_.idle_exit_s);
  for (;;) {
    if (stop && stop()) break;
    const auto now = Clock::now();
    if (now - last_info >= info_period) publishInfo();
    if (commanded && !safe && now - last_command > watchdog) {
      (void)device_.onWrite(zero, false);
      safe = true;
      ++result.watchdog_trips;
      publisher.setNodeState(last_seq, true);
      log("watchdog: no command for " + seconds(options_.watchdog_timeout_s) +
          ": safe outputs (valves null, amplifiers disabled)");
    }
    if (options_.idle_exit_s > 0.0 && now - last_command > idle) {
      log(commanded ? "no command for " + seconds(options_.idle_exit_s) + ": stopped"
                    : "no tick connected within " + seconds(options_.idle_exit_s) + ": stopped");
      break;
    }
    have_command = false;
    if (rx.handleTimeout(5) <= 0 || !have_command) continue;
    const SequenceTracker::Verdict verdict = command_seq.accept(command.seq);
    if (verdict == SequenceTracker::Verdict::kStale) {
      ++result.stale_commands;
      continue;
    }
    if (verdict == SequenceTracker::Verdict::kRestart) {
      log("commands restarted at seq " + std::to_string(command.seq) + ": a new tick connected");
    }
    if (command.num_valves != device_.numJoints()) {
      ++result.rejected;
      log("a command for " + std::to_string(command.num_valves) + " valves ignored: this node serves " +
          std::to_string(device_.numJoints()));
      continue;
    }
    last_seq = command.seq;
    last_command = Clock::now();
    if (!commanded) log("first command");
    commanded = true;
    for (int k = 0; k < valve.size(); ++k) valve[k] = command.valve_command_v[static_cast<std::size_t>(k)];
    const bool enable = command.enable != 0;
    if (safe && enable) log("amplifiers enabled: commands applied");
    (void)device_.onWrite(enable ? valve : zero, enable);
    safe = !enable;
    const core::RtStatus status = device_.onRead(sample);
    ++result.commands;
    publisher.setNodeState(last_seq, safe);

    fullarm_lcm::io_reading_t reading{};
    reading.utime = wallMicros();
    reading.seq = command.seq;
    reading.t_s = sample.t_s;
    reading.num_joints = static_cast<std::int8_t>(device_.numJoints());
    reading.q_rad.assign(sample.q_rad.data(), sample.q_rad.data() + sample.q_rad.size());
    reading.tau_load_cell_nm.assign(sample.tau_load_cell_nm.data(),
                                    sample.tau_load_cell_nm.data() + sample.tau_load_cell_nm.size());
    reading.out_of_range_mask = static_cast<std::int32_t>(sample.out_of_range_mask);
    // The chamber pressures where the back-end read them; zero elsewhere.
    const auto n = static_cast<std::size_t>(device_.numJoints());
    const bool has_pressures =
        sample.p_a_pa.size() == device_.numJoints() && sample.p_b_pa.size() == device_.numJoints();
    const std::uint32_t joint_bits = (1u << n) - 1u;
    reading.pressure_mask = has_pressures ? static_cast<std::int32_t>(sample.pressure_mask & joint_bits) : 0;
    reading.p_a_pa.assign(n, 0.0);
    reading.p_b_pa.assign(n, 0.0);
    for (std::size_t k = 0; k < n; ++k) {
      if ((static_cast<std::uint32_t>(reading.pressure_mask) >> k) & 1u) {
        reading.p_a_pa[k] = sample.p_a_pa[static_cast<Eigen::Index>(k)];
        reading.p_b_pa[k] = sample.p_b_pa[static_cast<Eigen::Index>(k)];
      }
    }
    reading.status_code = static_cast<std::int8_t>(status.code);
    reading.status_faults = static_cast<std::int32_t>(status.faults);
    reading.description_id = description_id;
    encodeMessage(reading, buffer);
    if (tx.publish(channel::kIoReading, buffer.data(), static_cast<unsigned int>(buffer.size())) != 0) {
      log("a reading could not be sent");
    }
  }
  if (!safe) {
    (void)device_.onWrite(zero, false);
    safe = true;
  }
  result.safe_at_exit = safe;
  return result;
}

}  // namespace fullarm::hil
