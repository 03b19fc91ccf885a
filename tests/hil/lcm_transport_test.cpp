// The LCM transport over LCM's in-process queue (memq://): fragments under a datagram's size,
// sets reassembled bit for bit, the newest message kept, lost and out-of-order fragments and
// sets dropped and counted, heartbeats, and the publisher's real-time side not allocating.

#include "fullarm/hil/lcm_transport.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <memory>
#include <random>
#include <thread>

#include "alloc_guard.hpp"

namespace fullarm::hil {
namespace {

bool sameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// A set of `n` minima whose every field differs (and follows from `id`).
MinimaSetRecord makeSet(std::int64_t id, int n) {
  MinimaSetRecord s;
  s.utime_us = 1000 * id;
  s.set_id = id;
  s.computed_tick = 10 * id;
  s.computed_utime_us = 10000 * id;
  s.adopted_tick = -1;
  s.num_joints = 7;
  for (int j = 0; j < 7; ++j) s.q_rad[static_cast<std::size_t>(j)] = 0.1 * j + 1e-3 * static_cast<double>(id) + 1.0 / 3.0;
  s.num_minima = n;
  s.num_minima_dropped = 2;
  for (int i = 0; i < n; ++i) {
    MinimumRecord& m = s.minima[static_cast<std::size_t>(i)];
    m.link = i % 7;
    m.object = i % 5;
    m.tri_link = 1000 + i;
    m.tri_object = 2000 + i;
    m.feature_link_kind = static_cast<std::int8_t>(i % 3);
    m.feature_link_index = 3000 + i;
    m.feature_object_kind = static_cast<std::int8_t>((i + 1) % 3);
    m.feature_object_index = 4000 + i;
    m.p_link_m = {std::sqrt(2.0) * i, -1.0 / (i + 1), 0.5};
    m.p_object_m = {std::exp(-0.1 * i), 1e-17 * i, -3.0};
    m.distance_m = 0.001 * i + 1e-9;
    m.u_world_unit = {0.6, 0.8, 0.0};
    m.previous_distance_m = i == 0 ? std::nan("") : 0.002 * i;
  }
  return s;
}

/// Field-by-field, bit-for-bit equality of two sets.
void expectSameSet(const MinimaSetRecord& a, const MinimaSetRecord& b) {
  EXPECT_EQ(a.set_id, b.set_id);
  EXPECT_EQ(a.computed_tick, b.computed_tick);
  EXPECT_EQ(a.computed_utime_us, b.computed_utime_us);
  EXPECT_EQ(a.adopted_tick, b.adopted_tick);
  EXPECT_EQ(a.num_minima_dropped, b.num_minima_dropped);
  ASSERT_EQ(a.num_joints, b.num_joints);
  for (int j = 0; j < a.num_joints; ++j) EXPECT_TRUE(sameBits(a.q_rad[static_cast<std::size_t>(j)], b.q_rad[static_cast<std::size_t>(j)]));
  ASSERT_EQ(a.num_minima, b.num_minima);
  for (int i = 0; i < a.num_minima; ++i) {
    const MinimumRecord& x = a.minima[static_cast<std::size_t>(i)];
    const MinimumRecord& y = b.minima[static_cast<std::size_t>(i)];
    EXPECT_EQ(x.link, y.link);
    EXPECT_EQ(x.object, y.object);
    EXPECT_EQ(x.tri_link, y.tri_link);
    EXPECT_EQ(x.tri_object, y.tri_object);
    EXPECT_EQ(x.feature_link_kind, y.feature_link_kind);
    EXPECT_EQ(x.feature_link_index, y.feature_link_index);
    EXPECT_EQ(x.feature_object_kind, y.feature_object_kind);
    EXPECT_EQ(x.feature_object_index, y.feature_object_index);
    for (int k = 0; k < 3; ++k) {
      EXPECT_TRUE(sameBits(x.p_link_m[static_cast<std::size_t>(k)], y.p_link_m[static_cast<std::size_t>(k)]));
      EXPECT_TRUE(sameBits(x.p_object_m[static_cast<std::size_t>(k)], y.p_object_m[static_cast<std::size_t>(k)]));
      EXPECT_TRUE(sameBits(x.u_world_unit[static_cast<std::size_t>(k)], y.u_world_unit[static_cast<std::size_t>(k)]));
    }
    EXPECT_TRUE(sameBits(x.distance_m, y.distance_m));
    EXPECT_TRUE(sameBits(x.previous_distance_m, y.previous_distance_m));
  }
}

LcmPublisherOptions publisherOptions(NodeKind node, double heartbeat_period_s) {
  LcmPublisherOptions o;
  o.node = node;
  o.heartbeat_period_s = heartbeat_period_s;
  return o;
}

JointStateRecord makeJointState(std::int64_t seq) {
  JointStateRecord r;
  r.utime_us = 1000 * seq;
  r.seq = seq;
  r.tick = seq;
  r.num_joints = 7;
  for (int j = 0; j < 7; ++j) {
    r.q_rad[static_cast<std::size_t>(j)] = 0.01 * static_cast<double>(seq) + j;
    r.tau_measured_nm[static_cast<std::size_t>(j)] = -2.0 * j;
    r.valve_command_v[static_cast<std::size_t>(j)] = 0.5 * j;
  }
  return r;
}

/// The encoded fragments of a set, fragment seq numbers from `first_seq`.
std::vector<std::vector<std::uint8_t>> fragments(const MinimaSetRecord& set, std::int64_t first_seq) {
  std::vector<std::vector<std::uint8_t>> out;
  for (int i = 0; i < fragmentCount(set.num_minima); ++i) {
    out.emplace_back();
    encodeMessage(toFragment(set, i, first_seq + i), out.back());
  }
  return out;
}

TEST(LcmTransport, EveryFragmentOfAFullSetFitsOneDatagram) {
  const MinimaSetRecord set = makeSet(3, kMaxMinimaPerSet);
  const auto parts = fragments(set, 0);
  // ceil(128 / 10) fragments, each under the 1,400-byte bound.
  ASSERT_EQ(parts.size(), static_cast<std::size_t>((kMaxMinimaPerSet + kMaxMinimaPerFragment - 1) / kMaxMinimaPerFragment));
  for (const auto& p : parts) EXPECT_LT(p.size(), kMaxFragmentBytes);
}

TEST(LcmTransport, PublishedSetAndJointStatesArriveBitForBit) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  LcmReceiver rx(lcm, {.joint_state = true, .minima_set = true});
  LcmPublisher pub(lcm, publisherOptions(NodeKind::kGlobal, 0.0));
  const MinimaSetRecord sent = makeSet(7, 64);
  ASSERT_TRUE(pub.pushMinimaSet(sent));
  for (int k = 1; k <= 5; ++k) ASSERT_TRUE(pub.pushJointState(makeJointState(k)));
  pub.flush();
  EXPECT_GT(rx.drain(), 0);

  const MinimaSetRecord* got = rx.takeMinimaSet();
  ASSERT_NE(got, nullptr);
  expectSameSet(sent, *got);
  EXPECT_EQ(rx.takeMinimaSet(), nullptr);  // taken once
  EXPECT_EQ(pub.counters().minima_fragments, 6u);  // ceil(64 / 11)
  EXPECT_LT(pub.counters().largest_fragment_bytes, kMaxFragmentBytes);

  // Five joint states drained at once: the newest is kept, the others count as accepted.
  const JointStateRecord* js = rx.takeJointState();
  ASSERT_NE(js, nullptr);
  EXPECT_EQ(js->seq, 5);
  const JointStateRecord expected = makeJointState(5);
  for (int j = 0; j < 7; ++j) EXPECT_TRUE(sameBits(js->q_rad[static_cast<std::size_t>(j)], expected.q_rad[static_cast<std::size_t>(j)]));
  EXPECT_EQ(rx.takeJointState(), nullptr);
  EXPECT_EQ(rx.counters().joint_state.accepted, 5u);
  EXPECT_EQ(rx.counters().joint_state.gaps, 0u);
}

TEST(LcmTransport, OlderAndRepeatedJointStatesAreDroppedAndGapsCounted) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {.joint_state = true});
  std::vector<std::uint8_t> b;
  for (std::int64_t seq : {4, 2, 4, 9}) {
    encodeMessage(toMessage(makeJointState(seq)), b);
    rx.handle(channel::kJointState, b);
  }
  const LcmChannelCounters& c = rx.counters().joint_state;
  EXPECT_EQ(c.received, 4u);
  EXPECT_EQ(c.accepted, 2u);  // 4, 9
  EXPECT_EQ(c.stale, 2u);     // 2 (older), 4 (repeated)
  EXPECT_EQ(c.gaps, 4u);      // 5, 6, 7, 8 never came
  ASSERT_NE(rx.takeJointState(), nullptr);
  EXPECT_EQ(rx.takeJointState(), nullptr);
}

// A producer that restarts (its node restarted) counts from its first sequence number again.
TEST(LcmTransport, ASequenceTrackerHearsARestartedProducerButNotAnOldMessage) {
  using V = SequenceTracker::Verdict;
  SequenceTracker t;
  for (std::int64_t seq = 0; seq < 50; ++seq) ASSERT_EQ(t.accept(seq), V::kNewer) << seq;
  EXPECT_EQ(t.accept(47), V::kStale);  // a reordered or repeated message, alone
  EXPECT_EQ(t.accept(49), V::kStale);
  EXPECT_EQ(t.accept(50), V::kNewer);
  EXPECT_EQ(t.accept(0), V::kRestart);  // the producer's first number: restarted
  EXPECT_EQ(t.newest(), 0);
  EXPECT_EQ(t.accept(1), V::kNewer);
  EXPECT_EQ(t.restarts(), 1u);

  // Without its first message: heard after kRestartRun increasing older ones in a row.
  SequenceTracker u;
  for (std::int64_t seq = 0; seq < 500; ++seq) ASSERT_EQ(u.accept(seq), V::kNewer);
  EXPECT_EQ(u.accept(3), V::kStale);
  EXPECT_EQ(u.accept(4), V::kStale);
  static_assert(SequenceTracker::kRestartRun == 3);
  EXPECT_EQ(u.accept(6), V::kRestart);
  EXPECT_EQ(u.accept(7), V::kNewer);
  // A jump back beyond kRestartJump is a restart at once.
  SequenceTracker w;
  ASSERT_EQ(w.accept(SequenceTracker::kRestartJump + 10), V::kNewer);
  EXPECT_EQ(w.accept(5), V::kRestart);
  // A producer whose first number is 1 (a run's queries and commands).
  SequenceTracker q(1);
  ASSERT_EQ(q.accept(1), V::kNewer);
  ASSERT_EQ(q.accept(2), V::kNewer);
  EXPECT_EQ(q.accept(1), V::kRestart);
}

TEST(LcmTransport, ARestartedNodesHeartbeatsAreHeardAgain) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {.heartbeat = true});
  std::vector<std::uint8_t> b;
  const auto beat = [&](std::int64_t seq, std::int64_t tick) {
    HeartbeatRecord h;
    h.seq = seq;
    h.node = NodeKind::kGlobal;
    h.tick = tick;
    encodeMessage(toMessage(h), b);
    rx.handle(channel::kHeartbeat, b);
  };
  for (std::int64_t seq = 0; seq < 40; ++seq) beat(seq, 100 + seq);
  ASSERT_EQ(rx.lastHeartbeat(NodeKind::kGlobal)->tick, 139);
  beat(0, 7);  // the node restarted: its numbering starts again
  beat(1, 8);
  EXPECT_EQ(rx.heartbeatsFrom(NodeKind::kGlobal), 42u);
  EXPECT_EQ(rx.lastHeartbeat(NodeKind::kGlobal)->tick, 8);
  EXPECT_EQ(rx.counters().heartbeat.restarts, 1u);
  EXPECT_EQ(rx.counters().heartbeat.stale, 0u);
}

TEST(LcmTransport, ARestartedProducersMinimaSetsAreReassembledAgain) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {.minima_set = true});
  for (const auto& f : fragments(makeSet(50, 25), 0)) rx.handle(channel::kMinimaSet, f);
  ASSERT_NE(rx.takeMinimaSet(), nullptr);
  // The producer restarted its set numbering: set 1, 2 are older than 50 (dropped), the third
  // older set in a row, increasing, is a restart and is delivered, and the next one too.
  for (std::int64_t id : {1, 2}) {
    for (const auto& f : fragments(makeSet(id, 25), 10 * id)) rx.handle(channel::kMinimaSet, f);
    EXPECT_EQ(rx.takeMinimaSet(), nullptr) << "set " << id;
  }
  for (std::int64_t id : {3, 4}) {
    for (const auto& f : fragments(makeSet(id, 25), 10 * id)) rx.handle(channel::kMinimaSet, f);
    const MinimaSetRecord* got = rx.takeMinimaSet();
    ASSERT_NE(got, nullptr) << "set " << id;
    expectSameSet(makeSet(id, 25), *got);
  }
  // A jump back beyond kSetRestartJump is a restart at once.
  for (const auto& f : fragments(makeSet(5000, 25), 100)) rx.handle(channel::kMinimaSet, f);
  ASSERT_NE(rx.takeMinimaSet(), nullptr);
  for (const auto& f : fragments(makeSet(1, 25), 200)) rx.handle(channel::kMinimaSet, f);
  const MinimaSetRecord* got = rx.takeMinimaSet();
  ASSERT_NE(got, nullptr);
  EXPECT_EQ(got->set_id, 1);
}

TEST(LcmTransport, ASetMissingAFragmentIsDroppedAndCounted) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {.minima_set = true});
  // Set 1: fragments seq 0..2, the middle one withheld; set 2: seq 3..5, complete.
  LcmPublisherOptions options = publisherOptions(NodeKind::kGlobal, 0.0);
  options.drop = [](std::string_view ch, std::int64_t seq) { return ch == channel::kMinimaSet && seq == 1; };
  LcmPublisher pub(lcm, options);
  ASSERT_TRUE(pub.pushMinimaSet(makeSet(1, 25)));
  ASSERT_TRUE(pub.pushMinimaSet(makeSet(2, 25)));
  pub.flush();
  rx.drain();
  EXPECT_EQ(pub.counters().injected_drops, 1u);
  const LcmReceiverCounters& c = rx.counters();
  EXPECT_EQ(c.sets_completed, 1u);
  EXPECT_EQ(c.sets_incomplete, 1u);
  EXPECT_EQ(c.minima_fragment.gaps, 1u);
  const MinimaSetRecord* got = rx.takeMinimaSet();
  ASSERT_NE(got, nullptr);
  expectSameSet(makeSet(2, 25), *got);
}

TEST(LcmTransport, FragmentsInAnyOrderReassembleButAnOlderSetIsDropped) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {.minima_set = true});
  auto newer = fragments(makeSet(5, 64), 100);
  auto older = fragments(makeSet(4, 64), 90);
  std::mt19937 rng(11);
  std::shuffle(newer.begin(), newer.end(), rng);
  // The newer set's fragments, shuffled, with the older set's interleaved after its first.
  rx.handle(channel::kMinimaSet, newer[0]);
  for (const auto& f : older) rx.handle(channel::kMinimaSet, f);
  for (std::size_t i = 1; i < newer.size(); ++i) rx.handle(channel::kMinimaSet, newer[i]);
  // A repeated fragment after completion.
  rx.handle(channel::kMinimaSet, newer[3]);

  const LcmReceiverCounters& c = rx.counters();
  EXPECT_EQ(c.sets_completed, 1u);
  EXPECT_EQ(c.fragments_ignored, older.size() + 1);
  EXPECT_EQ(c.minima_fragment.stale, older.size() + 1);
  EXPECT_EQ(c.minima_fragment.accepted, newer.size());
  const MinimaSetRecord* got = rx.takeMinimaSet();
  ASSERT_NE(got, nullptr);
  expectSameSet(makeSet(5, 64), *got);
}

TEST(LcmTransport, AFragmentWhoseHeaderDisagreesWithItsSetIsRejected) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {.minima_set = true});
  const MinimaSetRecord set = makeSet(8, 30);
  MinimaSetRecord other = set;
  other.computed_tick += 1;  // same set id, another search: a corrupt or confused sender
  std::vector<std::uint8_t> b;
  encodeMessage(toFragment(set, 0, 0), b);
  rx.handle(channel::kMinimaSet, b);
  encodeMessage(toFragment(other, 1, 1), b);
  rx.handle(channel::kMinimaSet, b);
  EXPECT_EQ(rx.counters().minima_fragment.malformed, 1u);
  encodeMessage(toFragment(set, 1, 2), b);
  rx.handle(channel::kMinimaSet, b);
  encodeMessage(toFragment(set, 2, 3), b);
  rx.handle(channel::kMinimaSet, b);
  const MinimaSetRecord* got = rx.takeMinimaSet();
  ASSERT_NE(got, nullptr);
  expectSameSet(set, *got);
}

TEST(LcmTransport, HeartbeatsCarryTheNodeState) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {.heartbeat = true});
  {
    LcmPublisher pub(lcm, publisherOptions(NodeKind::kPlant, 0.005));
    pub.setNodeState(42, true);
    std::this_thread::sleep_for(std::chrono::milliseconds(40));
  }  // the publisher is stopped: nothing is published while the receiver drains
  rx.drain();
  EXPECT_GE(rx.heartbeatsFrom(NodeKind::kPlant), 2u);
  EXPECT_EQ(rx.heartbeatsFrom(NodeKind::kLocal), 0u);
  EXPECT_EQ(rx.lastHeartbeat(NodeKind::kGlobal), nullptr);
  const HeartbeatRecord* h = rx.lastHeartbeat(NodeKind::kPlant);
  ASSERT_NE(h, nullptr);
  EXPECT_EQ(h->tick, 42);
  EXPECT_TRUE(h->safe_output);
  EXPECT_EQ(h->seq + 1, static_cast<std::int64_t>(rx.heartbeatsFrom(NodeKind::kPlant)));
  EXPECT_EQ(rx.counters().heartbeat.gaps, 0u);
}

TEST(LcmTransport, PushingDoesNotAllocate) {
  lcm::LCM lcm("memq://");
  LcmPublisherOptions options = publisherOptions(NodeKind::kLocal, 0.0);
  options.minima_set_capacity = 2;
  LcmPublisher pub(lcm, options);
  const JointStateRecord js = makeJointState(1);
  ValveCommandRecord vc;
  vc.num_valves = 7;
  const auto set = std::make_unique<MinimaSetRecord>(makeSet(1, 64));
  EXPECT_NO_HEAP_ALLOCATION(pub.pushJointState(js));
  EXPECT_NO_HEAP_ALLOCATION(pub.pushValveCommand(vc));
  EXPECT_NO_HEAP_ALLOCATION(pub.pushMinimaSet(*set));
  EXPECT_NO_HEAP_ALLOCATION(pub.setNodeState(3, false));
  pub.flush();
  EXPECT_EQ(pub.counters().joint_states, 1u);
  EXPECT_EQ(pub.counters().valve_commands, 1u);
  EXPECT_EQ(pub.counters().minima_sets, 1u);
}

// While records keep coming the publisher thread polls its rings: a push at the loop's pace does
// not wake it (no futex call on the real-time side); only the first push after an idle pause
// does. Every record is still sent.
TEST(LcmTransport, PushesAtTheLoopsPaceDoNotWakeThePublisherThread) {
  lcm::LCM lcm("memq://");
  LcmPublisherOptions options = publisherOptions(NodeKind::kLocal, 0.0);
  options.poll_period_s = 100e-6;
  options.poll_window_s = 0.5;  // wide: a loaded machine may delay the pushing thread
  LcmPublisher pub(lcm, options);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // the thread is idle, asleep
  const int n = 200;
  auto next = std::chrono::steady_clock::now();
  for (int k = 1; k <= n; ++k) {
    ASSERT_TRUE(pub.pushJointState(makeJointState(k)));
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
  pub.flush();
  EXPECT_EQ(pub.counters().joint_states, static_cast<std::uint64_t>(n));
  // The first push found the thread asleep (a second may race with its going to sleep).
  EXPECT_GE(pub.counters().push_wakeups, 1u);
  EXPECT_LE(pub.counters().push_wakeups, 2u);

  // Without polling every push may have to wake it.
  options.poll_period_s = 0.0;
  LcmPublisher blocking(lcm, options);
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  for (int k = 1; k <= 20; ++k) {
    ASSERT_TRUE(blocking.pushJointState(makeJointState(k)));
    blocking.flush();  // sent: the thread goes back to sleep
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  EXPECT_EQ(blocking.counters().joint_states, 20u);
  EXPECT_GE(blocking.counters().push_wakeups, 10u);
}

// A set pushed while the publisher thread waits out a poll period goes out at that poll; a
// publisher that sends sets inline (the global node's setting) has sent every fragment when the
// push returns, in the same order and numbering, and with the same drop hook.
TEST(LcmTransport, InlineMinimaSetsAreSentBeforeThePushReturns) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  LcmReceiver rx(lcm, {.minima_set = true});
  const auto set = std::make_unique<MinimaSetRecord>(makeSet(1, 64));
  const auto k = static_cast<std::uint64_t>(fragmentCount(64));
  {
    LcmPublisherOptions options = publisherOptions(NodeKind::kGlobal, 0.0);
    options.poll_period_s = 0.6;  // far longer than any wake-up, even on a loaded machine
    options.poll_window_s = 10.0;
    LcmPublisher pub(lcm, options);
    ASSERT_TRUE(pub.pushJointState(makeJointState(1)));
    pub.flush();                                                 // a record went out: the thread now polls
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // flush's extra wakes are spent
    const std::uint64_t wakeups_before = pub.counters().push_wakeups;
    ASSERT_TRUE(pub.pushMinimaSet(*set));
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_EQ(pub.counters().minima_sets, 0u) << "sent before the poll period ended";
    EXPECT_EQ(pub.counters().push_wakeups, wakeups_before);  // no system call on the pushing side
    pub.flush();
    EXPECT_EQ(pub.counters().minima_fragments, k);
  }
  (void)rx.drain();
  ASSERT_NE(rx.takeMinimaSet(), nullptr);

  LcmPublisherOptions options = publisherOptions(NodeKind::kGlobal, 0.05);  // heartbeats beside
  options.send_minima_sets_inline = true;
  std::vector<std::int64_t> seen;
  options.drop = [&](std::string_view channel, std::int64_t seq) {
    if (channel == channel::kMinimaSet) seen.push_back(seq);
    return channel == channel::kMinimaSet && seq == static_cast<std::int64_t>(k) + 1;  // the second set loses one
  };
  LcmPublisher pub(lcm, options);
  for (int id = 2; id <= 4; ++id) {
    MinimaSetRecord s = makeSet(id, 64);
    ASSERT_TRUE(pub.pushMinimaSet(s));
    EXPECT_EQ(pub.counters().minima_sets, static_cast<std::uint64_t>(id - 1));  // already sent
    (void)rx.drain();
    const MinimaSetRecord* got = rx.takeMinimaSet();
    if (id == 3) {
      EXPECT_EQ(got, nullptr);
      continue;
    }
    ASSERT_NE(got, nullptr);
    expectSameSet(s, *got);
  }
  EXPECT_EQ(pub.counters().minima_fragments, 3 * k - 1);
  EXPECT_EQ(pub.counters().injected_drops, 1u);
  pub.stop();
  ASSERT_EQ(seen.size(), 3 * k);
  for (std::size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], static_cast<std::int64_t>(i));
}

}  // namespace
}  // namespace fullarm::hil
