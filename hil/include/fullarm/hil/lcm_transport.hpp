#pragma once
/// @file
/// The LCM transport between the nodes of a split run (plant, global search, local tick): the
/// checked decoders, a publisher thread fed by the real-time side, and a receiver that drains
/// its channels every cycle and keeps the newest message of each.
///
/// **Publishing off the real-time path.** The tick (or the search) pushes fixed-size records
/// into SpscRings (`LcmPublisher::pushJointState` and friends, @rt: no lock, no allocation, and
/// no system call while records keep coming: the publisher thread then polls its rings every
/// poll_period_s, with a timer slack of 1 ns so that a poll period is not stretched by the
/// kernel's default 50 µs; only the first push after an idle pause wakes it, one futex wake); the
/// publisher thread turns them into LCM messages, encodes and sends them, and sends the node's heartbeat at a
/// fixed period. A producer off the real-time path (the global node) may send its minima sets
/// itself instead (LcmPublisherOptions::send_minima_sets_inline), which spares a set the hand-over
/// to the publisher thread. A minima set travels as fragments of at most kMaxMinimaPerFragment minima
/// (toFragment), each under 1,400 bytes so the kernel never splits a datagram at the IP level
/// (one lost IP fragment loses the datagram), each with its own sequence number.
///
/// **Receiving.** `LcmReceiver::drain()` handles every message waiting without blocking, checks
/// it (`decodeChecked`: length, type hash, counts, fragment layout) and keeps, per channel, the
/// newest by sequence number: an older or repeated message is dropped and counted, never
/// adopted. Minima fragments are reassembled (MinimaSetAssembler): a set missing a fragment is
/// dropped when a newer set begins, and fragments of a set older than the one in progress are
/// dropped, both counted. A malformed, truncated or wrong-hash message is counted and ignored; nothing a
/// sender puts on the wire can make the receiver throw or crash.
///
///   lcm::LCM lcm(kDefaultLcmUrl);
///   LcmPublisher pub(lcm, {.node = NodeKind::kLocal});   // starts its thread
///   pub.pushJointState(record);                           // tick, @rt
///   LcmReceiver rx(lcm, {.minima_set = true});
///   rx.drain();                                           // each cycle
///   if (const MinimaSetRecord* s = rx.takeMinimaSet()) adopt(*s);

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <semaphore>
#include <span>
#include <string_view>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "fullarm/hil/log_records.hpp"
#include "fullarm/hil/spsc_ring.hpp"
#include "fullarm_lcm/heartbeat_t.hpp"

namespace fullarm::hil {

/// The default LCM URL of every node: UDP multicast with ttl=0, so no datagram leaves the
/// machine. A two-machine run passes a URL with ttl=1 (docs/hil.md).
inline constexpr const char* kDefaultLcmUrl = "udpm://239.255.76.67:7667?ttl=0";

namespace channel {
inline constexpr const char* kHeartbeat = "FULLARM_HEARTBEAT";
}  // namespace channel

/// The nodes of a split run (heartbeat_t.node).
enum class NodeKind : std::int8_t { kPlant = 0, kGlobal = 1, kLocal = 2 };
/// Number of NodeKind values.
inline constexpr int kNodeKinds = 3;

/// A node's heartbeat (heartbeat_t).
struct HeartbeatRecord {
  std::int64_t utime_us = 0;
  std::int64_t seq = 0;
  NodeKind node = NodeKind::kPlant;
  std::int64_t tick = -1;    ///< newest tick the node handled; -1 before the first
  bool safe_output = false;  ///< the node holds its safe outputs
};

[[nodiscard]] fullarm_lcm::heartbeat_t toMessage(const HeartbeatRecord& record);
/// @throws RecordError for a node outside NodeKind
[[nodiscard]] HeartbeatRecord fromMessage(const fullarm_lcm::heartbeat_t& message);

/// What decodeChecked made of a payload.
enum class DecodeStatus : std::uint8_t {
  kOk = 0,
  kTruncated,  ///< shorter than its own counts say (or shorter than the 8-byte type hash)
  kWrongHash,  ///< the type hash is not the expected type's
  kMalformed,  ///< decodes, but a count, a size or a field is out of its bounds, or bytes follow
};

/// Decodes an LCM payload into `out` and checks it: hash, length (no byte left over), and the
/// record's bounds (fromMessage, checkFragment). Never throws; `out` is unspecified unless the
/// result is kOk. Allocates (the message's vectors).
DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, JointStateRecord& out) noexcept;
/// @copydoc decodeChecked(std::span<const std::uint8_t>, JointStateRecord&)
DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, ValveCommandRecord& out) noexcept;
/// @copydoc decodeChecked(std::span<const std::uint8_t>, JointStateRecord&)
DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, HeartbeatRecord& out) noexcept;
/// One minima-set fragment, checked on its own (checkFragment). @copydoc decodeChecked(std::span<const std::uint8_t>,
/// JointStateRecord&)
DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::minima_set_t& out) noexcept;

/// Encodes an LCM message into `out` (resized to the encoded size).
template <class Message>
void encodeMessage(const Message& message, std::vector<std::uint8_t>& out) {
  const int n = message.getEncodedSize();
  out.resize(static_cast<std::size_t>(n));
  message.encode(out.data(), 0, n);
}

/// The newest sequence number of one producer, deciding whether a message is newer. A producer
/// that restarts (its node restarted) counts from the beginning again; it is heard again, as a
/// restart, when its message carries the producer's first sequence number, when its sequence
/// jumps back by more than kRestartJump, or after kRestartRun increasing messages in a row that
/// are all older than the newest. A single old, repeated or reordered message is stale.
class SequenceTracker {
 public:
  /// A backwards jump larger than this is a restart.
  static constexpr std::int64_t kRestartJump = 1000;
  /// This many increasing messages in a row, all older than the newest, are a restart.
  static constexpr int kRestartRun = 3;

  enum class Verdict : std::uint8_t { kNewer, kStale, kRestart };

  /// A producer whose first sequence number is 0 (LcmPublisher's).
  SequenceTracker() noexcept = default;
  /// `first_seq`: the first sequence number the producer sends.
  explicit SequenceTracker(std::int64_t first_seq) noexcept : first_(first_seq) {}

  /// The verdict on `seq`; kNewer and kRestart make it the newest. @rt
  Verdict accept(std::int64_t seq) noexcept {
    if (!have_ || seq > newest_) return take(seq, Verdict::kNewer);
    if (seq == first_ && newest_ != first_) return take(seq, Verdict::kRestart);
    std::int64_t back = 0;  // a difference beyond int64 (a damaged number) is far back too
    if (__builtin_sub_overflow(newest_, seq, &back) || back > kRestartJump) return take(seq, Verdict::kRestart);
    run_ = run_ > 0 && seq > run_last_ ? run_ + 1 : 1;
    run_last_ = seq;
    if (run_ >= kRestartRun) return take(seq, Verdict::kRestart);
    return Verdict::kStale;
  }
  /// The newest sequence number accepted; -1 if none.
  [[nodiscard]] std::int64_t newest() const noexcept { return have_ ? newest_ : -1; }
  /// Restarts heard.
  [[nodiscard]] std::uint64_t restarts() const noexcept { return restarts_; }

 private:
  Verdict take(std::int64_t seq, Verdict v) noexcept {
    newest_ = seq;
    have_ = true;
    run_ = 0;
    if (v == Verdict::kRestart) ++restarts_;
    return v;
  }
  std::int64_t first_ = 0;
  std::int64_t newest_ = 0;
  bool have_ = false;
  std::int64_t run_last_ = 0;
  int run_ = 0;
  std::uint64_t restarts_ = 0;
};

/// Datagram payload bound of a minima-set fragment: under a 1,500-byte MTU less the IP, UDP
/// and LCM headers, with margin.
inline constexpr std::size_t kMaxFragmentBytes = 1400;

// --- publisher ---------------------------------------------------------------------------------

/// Options of an LcmPublisher.
struct LcmPublisherOptions {
  NodeKind node = NodeKind::kLocal;        ///< the node whose heartbeat this publisher sends
  double heartbeat_period_s = 0.05;        ///< heartbeat period; <= 0: no heartbeat
  std::size_t joint_state_capacity = 256;  ///< records the rings hold before dropping
  std::size_t valve_command_capacity = 256;
  std::size_t minima_set_capacity = 4;
  /// While records are coming (one within poll_window_s), the thread looks at its rings every
  /// poll_period_s instead of waiting to be woken, so a push makes no system call; idle, it
  /// blocks and the first push wakes it. <= 0: always block (every push may wake the thread).
  double poll_period_s = 100e-6;
  double poll_window_s = 0.05;  ///< see poll_period_s
  /// pushMinimaSet encodes the set's fragments and publishes them on the calling thread, back to
  /// back, before it returns (allocates, locks, makes system calls): a set skips the hand-over to
  /// the publisher thread (its wake-up or poll, and that thread's scheduling while it sends). For
  /// a producer off the real-time path (the global node's search); false keeps pushMinimaSet @rt.
  bool send_minima_sets_inline = false;
  /// Fault injection: called with each message's channel and its sequence number (the
  /// fragment's for a minima set) just before it is sent, by the publisher thread or, for a set
  /// sent inline, by the pushing thread (never by both at once); true drops the message unsent
  /// (counted in `injected_drops`). Empty: nothing is dropped.
  std::function<bool(std::string_view channel, std::int64_t seq)> drop;
};

/// What an LcmPublisher did.
struct LcmPublisherCounters {
  std::uint64_t joint_states = 0;          ///< joint_state_t sent
  std::uint64_t valve_commands = 0;        ///< valve_command_t sent
  std::uint64_t minima_sets = 0;           ///< whole sets sent (every fragment)
  std::uint64_t minima_fragments = 0;      ///< minima_set_t fragments sent
  std::uint64_t heartbeats = 0;            ///< heartbeat_t sent
  std::uint64_t ring_drops = 0;            ///< records refused because a ring was full
  std::uint64_t send_errors = 0;           ///< lcm publish calls that failed
  std::uint64_t injected_drops = 0;        ///< messages the `drop` hook withheld
  std::size_t largest_fragment_bytes = 0;  ///< largest encoded minima_set_t fragment
  std::uint64_t push_wakeups = 0;          ///< pushes that had to wake the sleeping thread (a futex wake)
};

/// Publishes what the real-time side pushes, from its own thread, plus the node's heartbeat.
/// One thread pushes each kind of record (the rings are single-producer).
class LcmPublisher {
 public:
  /// Starts the publisher thread on `lcm` (which must outlive the publisher; LCM allows
  /// publishing from this thread while another handles).
  LcmPublisher(lcm::LCM& lcm, LcmPublisherOptions options);
  LcmPublisher(const LcmPublisher&) = delete;
  LcmPublisher& operator=(const LcmPublisher&) = delete;
  /// Sends what is still queued, then stops the thread.
  ~LcmPublisher();

  /// Queues a joint state; false (counted) if the ring is full. @rt
  bool pushJointState(const JointStateRecord& record) noexcept;
  /// Queues a valve command; false (counted) if the ring is full. @rt
  bool pushValveCommand(const ValveCommandRecord& record) noexcept;
  /// Queues a minima set (sent as fragments, back to back); false (counted) if the ring is
  /// full. @rt, unless `send_minima_sets_inline`: then it sends the set itself (false if it
  /// could not be encoded).
  bool pushMinimaSet(const MinimaSetRecord& record) noexcept;
  /// The tick and safe-output state the next heartbeats report. A heartbeat goes out only
  /// after everything pushed before this call. @rt
  void setNodeState(std::int64_t tick, bool safe_output) noexcept;

  /// Blocks until everything pushed before the call has been sent (not real time).
  void flush();
  /// Sends what is queued and stops the thread; idempotent.
  void stop();

  /// A snapshot of the counters (any thread).
  [[nodiscard]] LcmPublisherCounters counters() const noexcept;

 private:
  void run();
  void wake() noexcept;
  void wakeIfAsleep() noexcept;
  [[nodiscard]] bool ringsEmpty() const noexcept;
  /// Sends what the rings hold; true if it sent anything. Under send_mutex_.
  bool sendQueued();
  /// Sends one set's fragments, back to back. Under send_mutex_.
  void sendSet(const MinimaSetRecord& set);
  void sendHeartbeat();
  void publishBytes(const char* channel, const std::vector<std::uint8_t>& bytes, std::int64_t seq,
                    std::atomic<std::uint64_t>& sent);

  lcm::LCM& lcm_;
  LcmPublisherOptions options_;
  SpscRing<JointStateRecord> joint_states_;
  SpscRing<ValveCommandRecord> valve_commands_;
  SpscRing<MinimaSetRecord> minima_sets_;
  std::counting_semaphore<> wake_{0};
  std::atomic<bool> stop_{false};
  std::atomic<bool> asleep_{false};  ///< the thread blocks on wake_: a push must wake it
  std::atomic<std::int64_t> node_tick_{-1};
  std::atomic<bool> node_safe_{false};
  /// Held while sending: by the publisher thread, and by a pushing thread that sends its sets
  /// inline. It guards the buffers, the sequence numbers, the counters' writes and `drop`.
  std::mutex send_mutex_;
  std::vector<std::uint8_t> buffer_;
  std::vector<std::vector<std::uint8_t>> fragment_buffers_;  ///< one per fragment of a set
  std::int64_t fragment_seq_ = 0;
  std::int64_t heartbeat_seq_ = 0;
  std::atomic<std::uint64_t> joint_states_sent_{0}, valve_commands_sent_{0}, minima_sets_sent_{0},
      minima_fragments_sent_{0}, heartbeats_sent_{0}, send_errors_{0}, injected_drops_{0}, push_wakeups_{0};
  std::atomic<std::size_t> largest_fragment_bytes_{0};
  std::thread thread_;
};

// --- receiver ----------------------------------------------------------------------------------

/// The channels an LcmReceiver subscribes to.
struct LcmReceiverOptions {
  bool joint_state = false;
  bool valve_command = false;
  bool minima_set = false;
  bool heartbeat = false;
  /// Messages LCM queues per channel between two drains; beyond it LCM drops new ones. Large
  /// enough for a 128-minima set's 12 fragments several times over.
  int queue_capacity = 256;
};

/// What an LcmReceiver saw on one channel.
struct LcmChannelCounters {
  std::uint64_t received = 0;    ///< payloads handled
  std::uint64_t accepted = 0;    ///< decoded, checked and newer than anything before
  std::uint64_t truncated = 0;   ///< DecodeStatus::kTruncated
  std::uint64_t wrong_hash = 0;  ///< DecodeStatus::kWrongHash
  std::uint64_t malformed = 0;   ///< DecodeStatus::kMalformed (and fragments whose header disagrees with their set's)
  std::uint64_t stale = 0;       ///< not newer than the newest accepted (older or repeated seq)
  std::uint64_t gaps = 0;        ///< sequence numbers skipped between accepted messages (lost)
  std::uint64_t restarts = 0;    ///< the producer started counting again (SequenceTracker): heard again
  /// Sum of the rejections (truncated, wrong hash, malformed).
  [[nodiscard]] std::uint64_t rejected() const noexcept { return truncated + wrong_hash + malformed; }
};

/// What an LcmReceiver saw, per channel, and what became of the minima sets.
struct LcmReceiverCounters {
  LcmChannelCounters joint_state, valve_command, minima_fragment, heartbeat;
  std::uint64_t sets_completed = 0;     ///< minima sets reassembled and delivered
  std::uint64_t sets_incomplete = 0;    ///< sets dropped because a newer set began before they were whole
  std::uint64_t fragments_ignored = 0;  ///< fragments of an older set than the one in progress, or repeated
};

/// Drains subscribed LCM channels and keeps the newest message of each. One thread uses it.
class LcmReceiver {
 public:
  /// Subscribes to the channels `options` names on `lcm` (which must outlive the receiver).
  LcmReceiver(lcm::LCM& lcm, LcmReceiverOptions options);
  LcmReceiver(const LcmReceiver&) = delete;
  LcmReceiver& operator=(const LcmReceiver&) = delete;
  /// Unsubscribes.
  ~LcmReceiver();

  /// Handles every message waiting, without blocking; returns how many were handled.
  int drain();
  /// Waits up to `timeout_s` for a message, then drains; returns how many were handled.
  int drainWait(double timeout_s);
  /// Handles one payload as if it had arrived on `channel` (the path every received message
  /// takes; tests feed damaged payloads through it).
  void handle(std::string_view channel, std::span<const std::uint8_t> bytes);

  /// The newest joint state accepted since the last call, or nullptr.
  [[nodiscard]] const JointStateRecord* takeJointState() noexcept;
  /// The newest valve command accepted since the last call, or nullptr.
  [[nodiscard]] const ValveCommandRecord* takeValveCommand() noexcept;
  /// The newest whole minima set delivered since the last call, or nullptr.
  [[nodiscard]] const MinimaSetRecord* takeMinimaSet() noexcept;
  /// The newest heartbeat of `node`, or nullptr if none arrived yet.
  [[nodiscard]] const HeartbeatRecord* lastHeartbeat(NodeKind node) const noexcept;
  /// Heartbeats received from `node` (a supervisor compares it across cycles).
  [[nodiscard]] std::uint64_t heartbeatsFrom(NodeKind node) const noexcept;

  /// The counters.
  [[nodiscard]] const LcmReceiverCounters& counters() const noexcept { return counters_; }

 private:
  struct RawHandler;
  /// Accepts `seq` on a channel whose producer `tracker` follows; counts.
  static bool acceptSeq(std::int64_t seq, SequenceTracker& tracker, LcmChannelCounters& c) noexcept;

  lcm::LCM& lcm_;
  std::vector<lcm_subscription_t*> subscriptions_;
  std::unique_ptr<RawHandler> handler_;
  LcmReceiverCounters counters_;

  JointStateRecord joint_state_{}, joint_state_scratch_{};
  SequenceTracker joint_state_seq_;
  bool joint_state_new_ = false;
  ValveCommandRecord valve_command_{}, valve_command_scratch_{};
  SequenceTracker valve_command_seq_;
  bool valve_command_new_ = false;
  std::array<HeartbeatRecord, kNodeKinds> heartbeats_{};
  std::array<SequenceTracker, kNodeKinds> heartbeat_seq_{};
  std::array<std::uint64_t, kNodeKinds> heartbeat_count_{};
  fullarm_lcm::minima_set_t fragment_;
  std::int64_t fragment_seq_ = -1;
  MinimaSetAssembler assembler_;
  std::unique_ptr<MinimaSetRecord> minima_set_;
  bool minima_set_new_ = false;
};

}  // namespace fullarm::hil
