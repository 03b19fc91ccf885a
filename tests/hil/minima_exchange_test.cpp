#include "fullarm/hil/minima_exchange.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "alloc_guard.hpp"

namespace fullarm::hil {
namespace {

/// Fills `set` so that every field follows from `id`: a torn set (parts of two) shows.
void fillSet(MinimaSetRecord& set, std::int64_t id) {
  set.set_id = id;
  set.seq = id;
  set.computed_tick = 10 * id;
  set.num_joints = 7;
  for (int j = 0; j < 7; ++j) set.q_rad[static_cast<std::size_t>(j)] = 0.001 * static_cast<double>(id) + j;
  set.num_minima = static_cast<int>(id % (kMaxMinimaPerSet + 1));
  for (int i = 0; i < kMaxMinimaPerSet; ++i) {
    MinimumRecord& m = set.minima[static_cast<std::size_t>(i)];
    m.link = static_cast<int>(id % 7);
    m.object = i;
    m.distance_m = static_cast<double>(id) + 1e-3 * i;
    m.p_link_m = {static_cast<double>(id), 1.0 * i, -1.0};
  }
}

bool consistent(const MinimaSetRecord& set) {
  const std::int64_t id = set.set_id;
  if (set.seq != id || set.computed_tick != 10 * id || set.num_minima != static_cast<int>(id % (kMaxMinimaPerSet + 1))) {
    return false;
  }
  for (int j = 0; j < 7; ++j) {
    if (set.q_rad[static_cast<std::size_t>(j)] != 0.001 * static_cast<double>(id) + j) return false;
  }
  for (int i = 0; i < kMaxMinimaPerSet; ++i) {
    const MinimumRecord& m = set.minima[static_cast<std::size_t>(i)];
    if (m.link != static_cast<int>(id % 7) || m.object != i || m.distance_m != static_cast<double>(id) + 1e-3 * i ||
        m.p_link_m[0] != static_cast<double>(id)) {
      return false;
    }
  }
  return true;
}

TEST(MinimaExchange, NothingBeforeTheFirstPublish) {
  MinimaExchange ex;
  EXPECT_EQ(ex.takeNewest(), nullptr);
  EXPECT_EQ(ex.current(), nullptr);
}

TEST(MinimaExchange, TakesEachSetOnceAndThenReportsNothingNew) {
  MinimaExchange ex;
  fillSet(ex.writeSlot(), 1);
  ex.publish();
  const MinimaSetRecord* s = ex.takeNewest();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->set_id, 1);
  EXPECT_TRUE(consistent(*s));
  EXPECT_EQ(ex.takeNewest(), nullptr);
  ASSERT_NE(ex.current(), nullptr);
  EXPECT_EQ(ex.current()->set_id, 1);
  EXPECT_EQ(ex.published(), 1u);
  EXPECT_EQ(ex.taken(), 1u);
}

TEST(MinimaExchange, ReaderGetsTheNewestAndCountsTheSkipped) {
  MinimaExchange ex;
  MinimaSetRecord set;
  for (std::int64_t id = 1; id <= 5; ++id) {
    fillSet(set, id);
    ex.publish(set);
  }
  const MinimaSetRecord* s = ex.takeNewest();
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->set_id, 5);
  EXPECT_EQ(ex.overwritten(), 4u);
}

TEST(MinimaExchange, ATakenSetStaysUnchangedWhileTheWriterGoesOn) {
  MinimaExchange ex;
  fillSet(ex.writeSlot(), 1);
  ex.publish();
  const MinimaSetRecord* held = ex.takeNewest();
  ASSERT_NE(held, nullptr);
  // The writer fills and publishes many sets; none may land in the slot the reader holds.
  for (std::int64_t id = 2; id < 50; ++id) {
    fillSet(ex.writeSlot(), id);
    ex.publish();
    EXPECT_EQ(held->set_id, 1);
    EXPECT_TRUE(consistent(*held));
  }
  const MinimaSetRecord* next = ex.takeNewest();
  ASSERT_NE(next, nullptr);
  EXPECT_EQ(next->set_id, 49);
}

TEST(MinimaExchange, PublishAndTakeDoNotAllocate) {
  MinimaExchange ex;
  MinimaSetRecord set;
  fillSet(set, 3);
  EXPECT_NO_HEAP_ALLOCATION(ex.publish(set));
  EXPECT_NO_HEAP_ALLOCATION(fillSet(ex.writeSlot(), 4); ex.publish());
  const MinimaSetRecord* s = nullptr;
  EXPECT_NO_HEAP_ALLOCATION(s = ex.takeNewest());
  ASSERT_NE(s, nullptr);
  EXPECT_EQ(s->set_id, 4);
}

// The global search and the tick on two threads: every set the reader takes is whole (never
// parts of two), set ids only increase, and the last set published is the last one taken.
TEST(MinimaExchange, TwoThreadsNeverATornSetAndIdsIncrease) {
  constexpr std::int64_t kSets = 20000;
  MinimaExchange ex;
  std::atomic<bool> writer_done{false};
  std::thread writer([&] {
    for (std::int64_t id = 1; id <= kSets; ++id) {
      fillSet(ex.writeSlot(), id);
      ex.publish();
    }
    writer_done.store(true, std::memory_order_release);
  });
  std::int64_t last = 0;
  std::uint64_t torn = 0;
  std::uint64_t backwards = 0;
  std::uint64_t taken = 0;
  for (;;) {
    const bool done = writer_done.load(std::memory_order_acquire);
    if (const MinimaSetRecord* s = ex.takeNewest()) {
      ++taken;
      if (!consistent(*s)) ++torn;
      if (s->set_id <= last) ++backwards;
      last = s->set_id;
    } else if (done) {
      break;
    }
  }
  writer.join();
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kSets);
  EXPECT_EQ(ex.taken(), taken);
  EXPECT_EQ(ex.taken() + ex.overwritten(), static_cast<std::uint64_t>(kSets));
}

}  // namespace
}  // namespace fullarm::hil
