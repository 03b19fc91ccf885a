#include "fullarm/hil/lcm_transport.hpp"

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <exception>
#include <mutex>
#include <string>

#include <sys/prctl.h>

#include "lcm_subscribe.hpp"

namespace fullarm::hil {
namespace {

/// The 8-byte big-endian type hash that starts every LCM payload.
std::int64_t readHash(std::span<const std::uint8_t> b) noexcept {
  std::uint64_t h = 0;
  for (int i = 0; i < 8; ++i) h = (h << 8) | b[static_cast<std::size_t>(i)];
  return static_cast<std::int64_t>(h);
}

/// Decodes `bytes` as a `Message` with every length and hash check; no record-level checks.
template <class Message>
DecodeStatus decodeRaw(std::span<const std::uint8_t> bytes, Message& message) noexcept {
  if (bytes.size() > static_cast<std::size_t>(INT_MAX)) return DecodeStatus::kMalformed;
  if (bytes.size() < 8) return DecodeStatus::kTruncated;
  if (readHash(bytes) != Message::getHash()) return DecodeStatus::kWrongHash;
  const int size = static_cast<int>(bytes.size());
  try {
    // A negative count makes the generated decoder resize a vector to a huge size, which
    // throws (std::length_error): malformed, not a crash.
    const int used = message.decode(bytes.data(), 0, size);
    if (used < 0) return DecodeStatus::kTruncated;
    if (used != size) return DecodeStatus::kMalformed;
  } catch (const std::exception&) {
    return DecodeStatus::kMalformed;
  }
  return DecodeStatus::kOk;
}

/// decodeRaw, then the record's conversion (which checks counts and sizes).
template <class Message, class Record>
DecodeStatus decodeToRecord(std::span<const std::uint8_t> bytes, Record& out) noexcept {
  try {
    Message message;
    const DecodeStatus status = decodeRaw(bytes, message);
    if (status != DecodeStatus::kOk) return status;
    out = fromMessage(message);
  } catch (const std::exception&) {
    return DecodeStatus::kMalformed;  // RecordError, or an allocation that failed
  }
  return DecodeStatus::kOk;
}

void count(DecodeStatus status, LcmChannelCounters& c) noexcept {
  switch (status) {
    case DecodeStatus::kOk:
      break;
    case DecodeStatus::kTruncated:
      ++c.truncated;
      break;
    case DecodeStatus::kWrongHash:
      ++c.wrong_hash;
      break;
    case DecodeStatus::kMalformed:
      ++c.malformed;
      break;
  }
}

void increment(std::atomic<std::uint64_t>& n) noexcept {
  n.store(n.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
}

}  // namespace

fullarm_lcm::heartbeat_t toMessage(const HeartbeatRecord& r) {
  fullarm_lcm::heartbeat_t m{};
  m.utime = r.utime_us;
  m.seq = r.seq;
  m.node = static_cast<std::int8_t>(r.node);
  m.tick = r.tick;
  m.safe_output = r.safe_output ? 1 : 0;
  return m;
}

HeartbeatRecord fromMessage(const fullarm_lcm::heartbeat_t& m) {
  if (m.node < 0 || m.node >= kNodeKinds) {
    throw RecordError("heartbeat_t.node = " + std::to_string(m.node) + ": expected 0 (plant), 1 (global) or 2 (local)");
  }
  HeartbeatRecord r;
  r.utime_us = m.utime;
  r.seq = m.seq;
  r.node = static_cast<NodeKind>(m.node);
  r.tick = m.tick;
  r.safe_output = m.safe_output != 0;
  return r;
}

DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, JointStateRecord& out) noexcept {
  return decodeToRecord<fullarm_lcm::joint_state_t>(bytes, out);
}

DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, ValveCommandRecord& out) noexcept {
  return decodeToRecord<fullarm_lcm::valve_command_t>(bytes, out);
}

DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, HeartbeatRecord& out) noexcept {
  return decodeToRecord<fullarm_lcm::heartbeat_t>(bytes, out);
}

DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::minima_set_t& out) noexcept {
  try {
    const DecodeStatus status = decodeRaw(bytes, out);
    if (status != DecodeStatus::kOk) return status;
    checkFragment(out);
  } catch (const std::exception&) {
    return DecodeStatus::kMalformed;
  }
  return DecodeStatus::kOk;
}

// --- publisher ---------------------------------------------------------------------------------

LcmPublisher::LcmPublisher(lcm::LCM& lcm, LcmPublisherOptions options)
    : lcm_(lcm),
      options_(std::move(options)),
      joint_states_(options_.joint_state_capacity),
      valve_commands_(options_.valve_command_capacity),
      minima_sets_(options_.minima_set_capacity),
      fragment_buffers_(static_cast<std::size_t>(fragmentCount(kMaxMinimaPerSet))) {
  thread_ = std::thread([this] { run(); });
}

LcmPublisher::~LcmPublisher() {
  stop();
}

void LcmPublisher::wake() noexcept {
  // The count only grows by one per wake and the thread takes one per pass: far below max().
  wake_.release();
}

void LcmPublisher::wakeIfAsleep() noexcept {
  // The record is in its ring (release store). Both sides exchange `asleep_` (read-modify-write,
  // acquire-release): if this exchange comes first, the thread's exchange reads it and then sees
  // the record; if the thread's comes first, this one reads true and wakes it. While the thread
  // polls, nothing more happens here: no system call.
  if (asleep_.exchange(false, std::memory_order_acq_rel)) {
    increment(push_wakeups_);
    wake();
  }
}

bool LcmPublisher::pushJointState(const JointStateRecord& record) noexcept {
  const bool ok = joint_states_.tryPush(record);
  if (ok) wakeIfAsleep();
  return ok;
}

bool LcmPublisher::pushValveCommand(const ValveCommandRecord& record) noexcept {
  const bool ok = valve_commands_.tryPush(record);
  if (ok) wakeIfAsleep();
  return ok;
}

bool LcmPublisher::pushMinimaSet(const MinimaSetRecord& record) noexcept {
  if (options_.send_minima_sets_inline) {
    try {
      const std::lock_guard lock(send_mutex_);
      sendSet(record);
    } catch (const std::exception&) {
      return false;  // could not encode (an allocation failed)
    }
    return true;
  }
  const bool ok = minima_sets_.tryPush(record);
  if (ok) wakeIfAsleep();
  return ok;
}

void LcmPublisher::setNodeState(std::int64_t tick, bool safe_output) noexcept {
  node_safe_.store(safe_output, std::memory_order_release);
  node_tick_.store(tick, std::memory_order_release);
}

void LcmPublisher::publishBytes(const char* channel, const std::vector<std::uint8_t>& bytes, std::int64_t seq,
                                std::atomic<std::uint64_t>& sent) {
  if (options_.drop && options_.drop(channel, seq)) {
    increment(injected_drops_);
    return;
  }
  if (lcm_.publish(channel, bytes.data(), static_cast<unsigned int>(bytes.size())) != 0) {
    increment(send_errors_);
    return;
  }
  increment(sent);
}

bool LcmPublisher::sendQueued() {
  std::size_t n = 0;
  n += joint_states_.consumeAll([this](const JointStateRecord& r) {
    encodeMessage(toMessage(r), buffer_);
    publishBytes(channel::kJointState, buffer_, r.seq, joint_states_sent_);
  });
  n += valve_commands_.consumeAll([this](const ValveCommandRecord& r) {
    encodeMessage(toMessage(r), buffer_);
    publishBytes(channel::kValveCommand, buffer_, r.seq, valve_commands_sent_);
  });
  n += minima_sets_.consumeAll([this](const MinimaSetRecord& set) { sendSet(set); });
  return n > 0;
}

void LcmPublisher::sendSet(const MinimaSetRecord& set) {
  // Every fragment is encoded first, then they go out back to back: the datagrams of a set
  // follow each other with nothing but the send calls between them.
  const int count = fragmentCount(set.num_minima);
  for (int i = 0; i < count; ++i) {
    std::vector<std::uint8_t>& bytes = fragment_buffers_[static_cast<std::size_t>(i)];
    encodeMessage(toFragment(set, i, fragment_seq_ + i), bytes);
    if (bytes.size() > largest_fragment_bytes_.load(std::memory_order_relaxed)) {
      largest_fragment_bytes_.store(bytes.size(), std::memory_order_relaxed);
    }
  }
  for (int i = 0; i < count; ++i) {
    const std::vector<std::uint8_t>& bytes = fragment_buffers_[static_cast<std::size_t>(i)];
    publishBytes(channel::kMinimaSet, bytes, fragment_seq_++, minima_fragments_sent_);
  }
  increment(minima_sets_sent_);
}

void LcmPublisher::sendHeartbeat() {
  // The state first, then what was pushed before it: a heartbeat never reports a tick whose
  // messages are still queued behind it.
  const std::int64_t tick = node_tick_.load(std::memory_order_acquire);
  const bool safe = node_safe_.load(std::memory_order_acquire);
  sendQueued();
  HeartbeatRecord h;
  h.utime_us =
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();
  h.seq = heartbeat_seq_;
  h.node = options_.node;
  h.tick = tick;
  h.safe_output = safe;
  encodeMessage(toMessage(h), buffer_);
  publishBytes(channel::kHeartbeat, buffer_, heartbeat_seq_++, heartbeats_sent_);
}

bool LcmPublisher::ringsEmpty() const noexcept {
  return joint_states_.pushed() == joint_states_.popped() && valve_commands_.pushed() == valve_commands_.popped() &&
         minima_sets_.pushed() == minima_sets_.popped();
}

void LcmPublisher::run() {
  // The kernel lets a timed wait of an ordinary thread end up to 50 µs late (its default timer
  // slack), half the poll period again; this thread's waits end on time.
  (void)::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  using Clock = std::chrono::steady_clock;
  const auto seconds = [](double s) {
    return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  };
  const bool beat = options_.heartbeat_period_s > 0.0;
  const auto period = seconds(beat ? options_.heartbeat_period_s : 1.0);
  const auto poll = seconds(options_.poll_period_s);
  const auto poll_window = seconds(options_.poll_window_s);
  auto next_beat = Clock::now();
  auto last_record = Clock::now() - poll_window;
  for (;;) {
    const bool stopping = stop_.load(std::memory_order_acquire);
    std::unique_lock lock(send_mutex_);  // a set sent inline by its pushing thread sends too
    if (sendQueued()) last_record = Clock::now();
    if (beat && Clock::now() >= next_beat) {
      sendHeartbeat();
      next_beat += period;
      if (next_beat < Clock::now()) next_beat = Clock::now() + period;  // no burst after a stall
    }
    lock.unlock();
    if (stopping) break;
    const auto now = Clock::now();
    const auto until = beat ? next_beat : now + period;
    if (options_.poll_period_s > 0.0 && now - last_record < poll_window) {
      // Records are coming: look again after one poll period, so that the pushing side never
      // has to wake this thread (no system call on the real-time side); flush() and stop() end
      // the wait early.
      (void)wake_.try_acquire_until(std::min(until, now + poll));
      // Spend wake-ups left over from flush()'s repeated releases, so the next poll waits its
      // full period instead of returning at once.
      while (wake_.try_acquire()) {
      }
      continue;
    }
    // Idle: block until a push wakes the thread (the first push after the pause pays one
    // futex wake-up), the next heartbeat, or stop().
    (void)asleep_.exchange(true, std::memory_order_acq_rel);
    if (ringsEmpty()) (void)wake_.try_acquire_until(until);
    asleep_.store(false, std::memory_order_relaxed);
  }
  const std::lock_guard lock(send_mutex_);
  sendQueued();
}

void LcmPublisher::flush() {
  const std::uint64_t js = joint_states_.pushed();
  const std::uint64_t vc = valve_commands_.pushed();
  const std::uint64_t ms = minima_sets_.pushed();
  // A ring frees its slots only after the visit published them: popped() counts sent records.
  while (thread_.joinable() &&
         (joint_states_.popped() < js || valve_commands_.popped() < vc || minima_sets_.popped() < ms)) {
    wake();
    std::this_thread::sleep_for(std::chrono::microseconds(50));
  }
}

void LcmPublisher::stop() {
  if (!thread_.joinable()) return;
  stop_.store(true, std::memory_order_release);
  wake();
  thread_.join();
}

LcmPublisherCounters LcmPublisher::counters() const noexcept {
  LcmPublisherCounters c;
  c.joint_states = joint_states_sent_.load(std::memory_order_relaxed);
  c.valve_commands = valve_commands_sent_.load(std::memory_order_relaxed);
  c.minima_sets = minima_sets_sent_.load(std::memory_order_relaxed);
  c.minima_fragments = minima_fragments_sent_.load(std::memory_order_relaxed);
  c.heartbeats = heartbeats_sent_.load(std::memory_order_relaxed);
  c.ring_drops = joint_states_.dropped() + valve_commands_.dropped() + minima_sets_.dropped();
  c.send_errors = send_errors_.load(std::memory_order_relaxed);
  c.injected_drops = injected_drops_.load(std::memory_order_relaxed);
  c.largest_fragment_bytes = largest_fragment_bytes_.load(std::memory_order_relaxed);
  c.push_wakeups = push_wakeups_.load(std::memory_order_relaxed);
  return c;
}

// --- receiver ----------------------------------------------------------------------------------

/// Forwards LCM's raw callbacks to LcmReceiver::handle.
struct LcmReceiver::RawHandler {
  LcmReceiver* receiver;
  void onMessage(std::span<const std::uint8_t> bytes, const char* channel) { receiver->handle(channel, bytes); }
};

LcmReceiver::LcmReceiver(lcm::LCM& lcm, LcmReceiverOptions options)
    : lcm_(lcm),
      handler_(std::make_unique<RawHandler>(RawHandler{this})),
      minima_set_(std::make_unique<MinimaSetRecord>()) {
  auto subscribe = [&](const char* name) {
    lcm_subscription_t* s = detail::subscribeRaw(lcm_, name, handler_.get(), options.queue_capacity);
    if (s == nullptr) throw std::runtime_error(std::string("LCM: cannot subscribe to channel ") + name);
    subscriptions_.push_back(s);
  };
  if (options.joint_state) subscribe(channel::kJointState);
  if (options.valve_command) subscribe(channel::kValveCommand);
  if (options.minima_set) subscribe(channel::kMinimaSet);
  if (options.heartbeat) subscribe(channel::kHeartbeat);
}

LcmReceiver::~LcmReceiver() {
  for (lcm_subscription_t* s : subscriptions_) lcm_unsubscribe(lcm_.getUnderlyingLCM(), s);
}

int LcmReceiver::drain() {
  int n = 0;
  while (lcm_.handleTimeout(0) > 0) ++n;
  return n;
}

int LcmReceiver::drainWait(double timeout_s) {
  if (detail::handleWithin(lcm_, timeout_s) <= 0) return 0;
  return 1 + drain();
}

bool LcmReceiver::acceptSeq(std::int64_t seq, SequenceTracker& tracker, LcmChannelCounters& c) noexcept {
  const std::int64_t newest = tracker.newest();
  switch (tracker.accept(seq)) {
    case SequenceTracker::Verdict::kStale:
      ++c.stale;
      return false;
    case SequenceTracker::Verdict::kRestart:
      ++c.restarts;
      break;
    case SequenceTracker::Verdict::kNewer:
      if (newest >= 0 && seq > newest + 1) c.gaps += static_cast<std::uint64_t>(seq - newest - 1);
      break;
  }
  ++c.accepted;
  return true;
}

void LcmReceiver::handle(std::string_view channel, std::span<const std::uint8_t> bytes) {
  if (channel == channel::kJointState) {
    LcmChannelCounters& c = counters_.joint_state;
    ++c.received;
    const DecodeStatus status = decodeChecked(bytes, joint_state_scratch_);
    count(status, c);
    if (status == DecodeStatus::kOk && acceptSeq(joint_state_scratch_.seq, joint_state_seq_, c)) {
      joint_state_ = joint_state_scratch_;
      joint_state_new_ = true;
    }
  } else if (channel == channel::kValveCommand) {
    LcmChannelCounters& c = counters_.valve_command;
    ++c.received;
    const DecodeStatus status = decodeChecked(bytes, valve_command_scratch_);
    count(status, c);
    if (status == DecodeStatus::kOk && acceptSeq(valve_command_scratch_.seq, valve_command_seq_, c)) {
      valve_command_ = valve_command_scratch_;
      valve_command_new_ = true;
    }
  } else if (channel == channel::kHeartbeat) {
    LcmChannelCounters& c = counters_.heartbeat;
    ++c.received;
    HeartbeatRecord h;
    const DecodeStatus status = decodeChecked(bytes, h);
    count(status, c);
    if (status != DecodeStatus::kOk) return;
    const auto k = static_cast<std::size_t>(h.node);
    if (acceptSeq(h.seq, heartbeat_seq_[k], c)) {
      heartbeats_[k] = h;
      ++heartbeat_count_[k];
    }
  } else if (channel == channel::kMinimaSet) {
    LcmChannelCounters& c = counters_.minima_fragment;
    ++c.received;
    const DecodeStatus status = decodeChecked(bytes, fragment_);
    count(status, c);
    if (status != DecodeStatus::kOk) return;
    // Fragments of one set may arrive in any order: the sequence number only counts losses;
    // ordering is the assembler's (by set id).
    if (fragment_seq_ >= 0 && fragment_.seq > fragment_seq_ + 1) {
      c.gaps += static_cast<std::uint64_t>(fragment_.seq - fragment_seq_ - 1);
    }
    fragment_seq_ = std::max(fragment_seq_, fragment_.seq);
    const std::uint64_t ignored_before = assembler_.ignored();
    bool complete = false;
    try {
      complete = assembler_.add(fragment_);
    } catch (const RecordError&) {
      ++c.malformed;  // its header disagrees with its set's other fragments
      return;
    }
    if (assembler_.ignored() != ignored_before) {
      ++c.stale;
    } else {
      ++c.accepted;
    }
    counters_.fragments_ignored = assembler_.ignored();
    counters_.sets_incomplete = assembler_.abandoned();
    if (!complete) return;
    // The assembler only ever completes a set newer than every set it completed before.
    *minima_set_ = assembler_.set();
    minima_set_new_ = true;
    ++counters_.sets_completed;
  }
}

const JointStateRecord* LcmReceiver::takeJointState() noexcept {
  if (!joint_state_new_) return nullptr;
  joint_state_new_ = false;
  return &joint_state_;
}

const ValveCommandRecord* LcmReceiver::takeValveCommand() noexcept {
  if (!valve_command_new_) return nullptr;
  valve_command_new_ = false;
  return &valve_command_;
}

const MinimaSetRecord* LcmReceiver::takeMinimaSet() noexcept {
  if (!minima_set_new_) return nullptr;
  minima_set_new_ = false;
  return minima_set_.get();
}

const HeartbeatRecord* LcmReceiver::lastHeartbeat(NodeKind node) const noexcept {
  const auto k = static_cast<std::size_t>(node);
  return heartbeat_count_[k] > 0 ? &heartbeats_[k] : nullptr;
}

std::uint64_t LcmReceiver::heartbeatsFrom(NodeKind node) const noexcept {
  return heartbeat_count_[static_cast<std::size_t>(node)];
}

}  // namespace fullarm::hil
