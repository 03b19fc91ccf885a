#include "fullarm/hil/lcm_io.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string_view>

#include "lcm_node.hpp"

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

}  // namespace

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
      out.tau_load_cell_nm.size() != n) {
    return DecodeStatus::kMalformed;
  }
  if (out.status_code < 0 || out.status_code > static_cast<int>(core::RtCode::kSolverFailure))
    return DecodeStatus::kMalformed;
  return DecodeStatus::kOk;
}

// --- the lcm back-end --------------------------------------------------------------------------

/// Receives the node's readings and heartbeats for an LcmIoDevice.
struct LcmIoDevice::Handler {
  fullarm_lcm::io_reading_t reading;
  bool have_reading = false;  ///< `reading` answers the current command
  std::int64_t want_seq = 0;
  std::uint64_t heartbeats = 0;
  LcmIoCounters* counters = nullptr;

  void onMessage(std::span<const std::uint8_t> bytes, const char* channel) {
    if (std::string_view(channel) == channel::kHeartbeat) {
      onHeartbeat(bytes);
    } else {
      onReading(bytes);
    }
  }
  void onReading(std::span<const std::uint8_t> bytes) {
    fullarm_lcm::io_reading_t m;
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
  held_v_ = IoVector::Zero(numJoints());
}

LcmIoDevice::~LcmIoDevice() = default;

void LcmIoDevice::onConfigure() {
  lcm_ = std::make_unique<lcm::LCM>(options_.url);
  if (!lcm_->good()) throw DeviceError("lcm I/O: cannot open the LCM URL " + options_.url);
  handler_ = std::make_unique<Handler>();
  handler_->counters = &counters_;
  // Subscriptions end with the LCM instance (lcm_destroy).
  lcm_subscription_t* r = detail::subscribeRaw(*lcm_, channel::kIoReading, handler_.get(), 64);
  lcm_subscription_t* h = detail::subscribeRaw(*lcm_, channel::kHeartbeat, handler_.get(), 64);
  if (r == nullptr || h == nullptr) throw DeviceError("lcm I/O: cannot subscribe on " + options_.url);
  const auto deadline = detail::after(options_.connect_timeout_s);
  while (handler_->heartbeats == 0 && Clock::now() < deadline) lcm_->handleTimeout(detail::millisUntil(deadline) + 1);
  if (handler_->heartbeats == 0) {
    throw DeviceError("lcm I/O: no plant node answered on " + options_.url + " within " +
                      std::to_string(options_.connect_timeout_s) +
                      " s (start `fullarm plant serve` with the same --lcm-url)");
  }
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
        return core::RtStatus::fault(core::RtCode::kBadState, kFaultDeviceRead | kFaultLinkLost,
                                     "lcm I/O: no reading from the I/O node in time (communication lost)");
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
  ++counters_.readings;
  const int n = numJoints();
  sample.q_rad.resize(n);
  sample.tau_load_cell_nm.resize(n);
  for (int k = 0; k < n; ++k) {
    sample.q_rad[k] = m.q_rad[static_cast<std::size_t>(k)];
    sample.tau_load_cell_nm[k] = m.tau_load_cell_nm[static_cast<std::size_t>(k)];
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
  fullarm_lcm::io_command_t c;
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

  device_.configure();  // safe outputs
  bool safe = true;
  std::int64_t last_seq = 0;
  SequenceTracker command_seq(1);  ///< the device counts its reads from 1: a new run is heard at once
  auto last_command = Clock::now();
  bool commanded = false;

  fullarm_lcm::io_command_t command;
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
  log("serving " + std::to_string(device_.numJoints()) + " joints on " + options_.url);

  JointSample sample;
  IoVector valve = IoVector::Zero(device_.numJoints());
  const IoVector zero = IoVector::Zero(device_.numJoints());
  std::vector<std::uint8_t> buffer;
  const auto watchdog = std::chrono::duration<double>(options_.watchdog_timeout_s);
  const auto idle = std::chrono::duration<double>(options_.idle_exit_s);
  for (;;) {
    if (stop && stop()) break;
    const auto now = Clock::now();
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

    fullarm_lcm::io_reading_t reading;
    reading.utime = wallMicros();
    reading.seq = command.seq;
    reading.t_s = sample.t_s;
    reading.num_joints = static_cast<std::int8_t>(device_.numJoints());
    reading.q_rad.assign(sample.q_rad.data(), sample.q_rad.data() + sample.q_rad.size());
    reading.tau_load_cell_nm.assign(sample.tau_load_cell_nm.data(),
                                    sample.tau_load_cell_nm.data() + sample.tau_load_cell_nm.size());
    reading.out_of_range_mask = static_cast<std::int32_t>(sample.out_of_range_mask);
    reading.status_code = static_cast<std::int8_t>(status.code);
    reading.status_faults = static_cast<std::int32_t>(status.faults);
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
