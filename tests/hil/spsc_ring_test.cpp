#include "fullarm/hil/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <deque>
#include <thread>
#include <vector>

#include "alloc_guard.hpp"

namespace fullarm::hil {
namespace {

/// A record whose every field follows from its sequence number, so a torn or stale read shows.
struct Record {
  std::uint64_t seq = 0;
  std::array<std::uint64_t, 13> payload{};
  std::uint64_t check = 0;
};

Record makeRecord(std::uint64_t seq) {
  Record r;
  r.seq = seq;
  for (std::size_t i = 0; i < r.payload.size(); ++i) r.payload[i] = seq * 2654435761u + i;
  r.check = ~seq;
  return r;
}

bool intact(const Record& r) {
  if (r.check != ~r.seq) return false;
  for (std::size_t i = 0; i < r.payload.size(); ++i) {
    if (r.payload[i] != r.seq * 2654435761u + i) return false;
  }
  return true;
}

TEST(SpscRing, CapacityIsTheNextPowerOfTwo) {
  EXPECT_EQ(SpscRing<int>(1).capacity(), 2u);
  EXPECT_EQ(SpscRing<int>(5).capacity(), 8u);
  EXPECT_EQ(SpscRing<int>(1024).capacity(), 1024u);
  EXPECT_THROW(SpscRing<int>(0), std::invalid_argument);
}

TEST(SpscRing, MatchesABoundedQueueOnAScriptedSequence) {
  // Against std::deque with the same bound: a scripted mix of pushes and pops, including a full
  // ring (pushes refused and counted) and an empty one (pops refused).
  SpscRing<int> ring(4);
  std::deque<int> peer;
  std::uint64_t peer_drops = 0;
  int next = 0;
  const char* script = "ppppppp ooo pp ooooooo ppppp o pppppppp oooooooooo p o";
  for (const char* c = script; *c != '\0'; ++c) {
    if (*c == 'p') {
      const bool fits = peer.size() < 4;
      EXPECT_EQ(ring.tryPush(next), fits);
      if (fits) {
        peer.push_back(next);
      } else {
        ++peer_drops;
      }
      ++next;
    } else if (*c == 'o') {
      int out = -1;
      const bool has = !peer.empty();
      EXPECT_EQ(ring.tryPop(out), has);
      if (has) {
        EXPECT_EQ(out, peer.front());
        peer.pop_front();
      }
    }
    EXPECT_EQ(ring.size(), peer.size());
  }
  EXPECT_EQ(ring.dropped(), peer_drops);
  EXPECT_GT(peer_drops, 0u);
}

TEST(SpscRing, ConsumeAllVisitsOldestFirstAndRespectsTheLimit) {
  SpscRing<int> ring(8);
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(ring.tryPush(i));
  std::vector<int> seen;
  EXPECT_EQ(ring.consumeAll([&](const int& v) { seen.push_back(v); }, 4), 4u);
  EXPECT_EQ(seen, (std::vector<int>{0, 1, 2, 3}));
  EXPECT_EQ(ring.consumeAll([&](const int& v) { seen.push_back(v); }), 2u);
  EXPECT_EQ(seen, (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(ring.consumeAll([&](const int&) { ADD_FAILURE(); }), 0u);
  EXPECT_EQ(ring.pushed(), 6u);
  EXPECT_EQ(ring.popped(), 6u);
}

TEST(SpscRing, TryPushWithFillsInPlaceAndSkipsTheFillWhenFull) {
  SpscRing<Record> ring(2);
  int fills = 0;
  for (std::uint64_t s = 0; s < 3; ++s) {
    ring.tryPushWith([&](Record& slot) noexcept {
      ++fills;
      slot = makeRecord(s);
    });
  }
  EXPECT_EQ(fills, 2);
  EXPECT_EQ(ring.dropped(), 1u);
  Record r;
  ASSERT_TRUE(ring.tryPop(r));
  EXPECT_EQ(r.seq, 0u);
  EXPECT_TRUE(intact(r));
}

TEST(SpscRing, PushAndPopDoNotAllocate) {
  SpscRing<Record> ring(16);
  const Record r = makeRecord(7);
  Record out;
  EXPECT_NO_HEAP_ALLOCATION(for (int i = 0; i < 40; ++i) ring.tryPush(r));  // 24 of them dropped, the ring full
  EXPECT_NO_HEAP_ALLOCATION(ring.tryPushWith([](Record& slot) noexcept { slot.seq = 1; }));
  EXPECT_NO_HEAP_ALLOCATION(ring.tryPop(out));
  std::uint64_t sum = 0;
  EXPECT_NO_HEAP_ALLOCATION(ring.consumeAll([&](const Record& x) { sum += x.seq; }));
  EXPECT_EQ(ring.dropped(), 25u);  // and the tryPushWith on the full ring
}

// Two threads: the producer never waits; whatever it pushed arrives whole, once, in order, and
// what it could not push is counted.
TEST(SpscRing, TwoThreadsLossyProducerEveryRecordWholeInOrderDropsCounted) {
  constexpr std::uint64_t kRecords = 200000;
  SpscRing<Record> ring(64);
  std::vector<std::uint64_t> accepted_seq;
  accepted_seq.reserve(kRecords);
  std::thread producer([&] {
    for (std::uint64_t s = 0; s < kRecords; ++s) {
      if (ring.tryPush(makeRecord(s))) accepted_seq.push_back(s);
    }
  });
  std::vector<std::uint64_t> received;
  received.reserve(kRecords);
  bool all_intact = true;
  for (;;) {
    const bool done = ring.pushed() + ring.dropped() == kRecords;  // read before draining
    ring.consumeAll([&](const Record& r) {
      all_intact = all_intact && intact(r);
      received.push_back(r.seq);
    });
    if (done && ring.size() == 0) break;
  }
  producer.join();
  ring.consumeAll([&](const Record& r) { received.push_back(r.seq); });
  EXPECT_TRUE(all_intact);
  EXPECT_EQ(received, accepted_seq);
  EXPECT_EQ(received.size() + ring.dropped(), kRecords);
}

TEST(SpscRing, TwoThreadsRetryingProducerDeliversEverything) {
  constexpr std::uint64_t kRecords = 200000;
  SpscRing<Record> ring(8);
  std::thread producer([&] {
    for (std::uint64_t s = 0; s < kRecords; ++s) {
      while (!ring.tryPush(makeRecord(s))) std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  bool ok = true;
  Record r;
  while (expected < kRecords) {
    if (ring.tryPop(r)) {
      ok = ok && intact(r) && r.seq == expected;
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_TRUE(ok);
  EXPECT_EQ(ring.pushed(), kRecords);
  EXPECT_EQ(ring.popped(), kRecords);
}

}  // namespace
}  // namespace fullarm::hil
