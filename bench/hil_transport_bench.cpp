// The tick's side of the hand-offs and the log writer's cost per tick record, each beside a
// peer in the same run:
//  - push + pop of one tick's joint-state record through SpscRing, and through a
//    mutex-protected std::deque (the plain way to hand records to another thread);
//  - a producer thread pushing while a consumer thread drains, for both;
//  - the newest-set hand-off of a 64-minimum set: MinimaExchange against a mutex-guarded copy;
//  - what the writer thread spends per tick record: record -> LCM message -> encode ->
//    lcm::LogFile::writeEvent (joint state, haptic status, and a 64-minimum set's fragments).

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cmath>
#include <deque>
#include <filesystem>
#include <atomic>
#include <mutex>
#include <thread>

#include "fullarm/hil/minima_exchange.hpp"
#include "fullarm/hil/run_log.hpp"
#include "fullarm/hil/spsc_ring.hpp"

namespace {

using namespace fullarm::hil;

JointStateRecord jointState(std::int64_t tick) {
  JointStateRecord r;
  r.utime_us = 1000 * tick;
  r.seq = tick;
  r.tick = tick;
  r.num_joints = 7;
  for (int j = 0; j < 7; ++j) {
    r.q_rad[static_cast<std::size_t>(j)] = std::sin(0.001 * static_cast<double>(tick) + j);
    r.tau_measured_nm[static_cast<std::size_t>(j)] = 3.0 * j;
    r.valve_command_v[static_cast<std::size_t>(j)] = 0.1 * j;
  }
  return r;
}

HapticStatusRecord hapticStatus(std::int64_t tick) {
  HapticStatusRecord r;
  r.utime_us = 1000 * tick;
  r.seq = tick;
  r.tick = tick;
  r.num_joints = 7;
  r.num_links = 7;
  for (int j = 0; j < 7; ++j) r.tau_contact_nm[static_cast<std::size_t>(j)] = 0.5 * j;
  return r;
}

MinimaSetRecord minimaSet(std::int64_t id, int n) {
  MinimaSetRecord s;
  s.set_id = id;
  s.num_joints = 7;
  s.num_minima = n;
  for (int i = 0; i < n; ++i) {
    s.minima[static_cast<std::size_t>(i)].link = i % 7;
    s.minima[static_cast<std::size_t>(i)].distance_m = 0.001 * i;
  }
  return s;
}

/// The peer: a std::deque behind a mutex, bounded like the ring.
template <class T>
class MutexQueue {
 public:
  explicit MutexQueue(std::size_t capacity) : capacity_(capacity) {}
  bool tryPush(const T& v) {
    std::lock_guard lock(mutex_);
    if (queue_.size() >= capacity_) return false;
    queue_.push_back(v);
    return true;
  }
  bool tryPop(T& out) {
    std::lock_guard lock(mutex_);
    if (queue_.empty()) return false;
    out = queue_.front();
    queue_.pop_front();
    return true;
  }

 private:
  std::size_t capacity_;
  std::mutex mutex_;
  std::deque<T> queue_;
};

void BM_RingPushPop(benchmark::State& state) {
  SpscRing<JointStateRecord> ring(1024);
  const JointStateRecord r = jointState(1);
  JointStateRecord out;
  for (auto _ : state) {
    ring.tryPush(r);
    ring.tryPop(out);
    benchmark::DoNotOptimize(out);
  }
}
BENCHMARK(BM_RingPushPop);

void BM_MutexDequePushPop(benchmark::State& state) {
  MutexQueue<JointStateRecord> queue(1024);
  const JointStateRecord r = jointState(1);
  JointStateRecord out;
  for (auto _ : state) {
    queue.tryPush(r);
    queue.tryPop(out);
    benchmark::DoNotOptimize(out);
  }
}
BENCHMARK(BM_MutexDequePushPop);

// Two threads: the timed thread pushes (the tick), a second one drains as fast as it can.
template <class Queue>
void pushWithDrainingConsumer(benchmark::State& state, Queue& queue) {
  std::atomic<bool> stop{false};
  std::thread consumer([&] {
    JointStateRecord out;
    while (!stop.load(std::memory_order_relaxed)) {
      if (!queue.tryPop(out)) std::this_thread::yield();
    }
  });
  const JointStateRecord r = jointState(1);
  std::int64_t refused = 0;
  for (auto _ : state) {
    if (!queue.tryPush(r)) ++refused;
  }
  stop = true;
  consumer.join();
  state.counters["refused"] = static_cast<double>(refused);
}

void BM_RingPushTwoThreads(benchmark::State& state) {
  SpscRing<JointStateRecord> ring(4096);
  pushWithDrainingConsumer(state, ring);
}
BENCHMARK(BM_RingPushTwoThreads)->UseRealTime();

void BM_MutexDequePushTwoThreads(benchmark::State& state) {
  MutexQueue<JointStateRecord> queue(4096);
  pushWithDrainingConsumer(state, queue);
}
BENCHMARK(BM_MutexDequePushTwoThreads)->UseRealTime();

void BM_MinimaExchangePublishTake64(benchmark::State& state) {
  MinimaExchange ex;
  const MinimaSetRecord set = minimaSet(1, 64);
  for (auto _ : state) {
    ex.publish(set);
    benchmark::DoNotOptimize(ex.takeNewest());
  }
}
BENCHMARK(BM_MinimaExchangePublishTake64);

void BM_MutexCopyPublishTake64(benchmark::State& state) {
  std::mutex mutex;
  MinimaSetRecord shared;
  MinimaSetRecord reader_copy;
  const MinimaSetRecord set = minimaSet(1, 64);
  for (auto _ : state) {
    {
      std::lock_guard lock(mutex);
      shared = set;
    }
    {
      std::lock_guard lock(mutex);
      reader_copy = shared;
    }
    benchmark::DoNotOptimize(reader_copy);
  }
}
BENCHMARK(BM_MutexCopyPublishTake64);

// The writer thread's work per record: message, encode, lcm::LogFile::writeEvent (to a file in
// the temporary folder; the stdio buffer reaches the kernel every 4 KiB).
template <class Record>
void encodeAndWrite(benchmark::State& state, const Record& record, const char* channel) {
  const auto file = std::filesystem::temp_directory_path() / ("fullarm_hil_bench_" + std::to_string(::getpid()) + ".lcmlog");
  {
    RunLogWriter writer({file});
    for (auto _ : state) writeRecord(writer, channel, record);
    state.counters["bytes_per_record"] =
        static_cast<double>(writer.stats().bytes_written) / static_cast<double>(state.iterations());
  }
  std::filesystem::remove(file);
}

void BM_EncodeWriteJointState(benchmark::State& state) {
  encodeAndWrite(state, jointState(5), channel::kJointState);
}
BENCHMARK(BM_EncodeWriteJointState);

void BM_EncodeWriteHapticStatus(benchmark::State& state) {
  encodeAndWrite(state, hapticStatus(5), channel::kHapticStatus);
}
BENCHMARK(BM_EncodeWriteHapticStatus);

void BM_EncodeWriteMinimaSet64(benchmark::State& state) {
  encodeAndWrite(state, minimaSet(5, 64), channel::kMinimaSet);
}
BENCHMARK(BM_EncodeWriteMinimaSet64);

}  // namespace

BENCHMARK_MAIN();
