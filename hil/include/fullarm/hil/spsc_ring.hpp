#pragma once
/// @file
/// SpscRing: a bounded, lock-free single-producer/single-consumer ring of fixed-size records,
/// the hand-off from the real-time tick to the threads that log and publish what it did.
///
/// One thread pushes (the tick), one thread pops (the log writer); each side only ever writes
/// its own index, and a record becomes visible to the consumer through a release store of the
/// producer's index (acquire on the other side), so a record is never read half written. Push
/// never blocks, never allocates and never waits for the consumer: when the ring is full the
/// record is dropped and counted (`dropped()`), so a slow disk can cost log records but never a
/// tick. The storage is allocated once, in the constructor.
///
///   SpscRing<JointStateRecord> ring(1024);          // capacity rounded up to a power of two
///   ring.tryPush(record);                           // tick thread, @rt
///   ring.consumeAll([](const JointStateRecord& r) { ... });  // writer thread

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <new>
#include <stdexcept>
#include <type_traits>

namespace fullarm::hil {

/// Bounded lock-free SPSC ring of trivially copyable records. Exactly one producer thread and
/// one consumer thread at a time (either may change between runs, with a happens-before edge
/// such as a thread join in between).
template <class T>
class SpscRing {
  static_assert(std::is_trivially_copyable_v<T>, "SpscRing holds trivially copyable records");

 public:
  /// Allocates room for at least `min_capacity` records (rounded up to a power of two, >= 2).
  /// @throws std::invalid_argument if min_capacity is 0 or above 2^30
  explicit SpscRing(std::size_t min_capacity);
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;

  /// Producer: appends a copy of `record`; false (and one more drop) if the ring is full.
  /// @rt
  bool tryPush(const T& record) noexcept;

  /// Producer: fills the next free slot in place with `fill(T&)` (no extra copy of a large
  /// record) and publishes it; false (and one more drop, `fill` not called) if the ring is
  /// full. The slot holds an older record's bytes on entry: `fill` must set every field it
  /// means to send. @rt when `fill` is.
  template <class Fill>
  bool tryPushWith(Fill&& fill) noexcept(noexcept(fill(std::declval<T&>())));

  /// Consumer: moves the oldest record into `out`; false if the ring is empty.
  /// @rt
  bool tryPop(T& out) noexcept;

  /// Consumer: calls `visit(const T&)` on up to `max_records` of the oldest records in place,
  /// oldest first, then frees their slots at once. Returns the number visited. @rt when
  /// `visit` is.
  template <class Visit>
  std::size_t consumeAll(Visit&& visit, std::size_t max_records = SIZE_MAX);

  /// Number of slots.
  [[nodiscard]] std::size_t capacity() const noexcept { return mask_ + 1; }
  /// Records waiting; exact from either side's own thread at the moment of the call, a snapshot
  /// from any other thread. @rt
  [[nodiscard]] std::size_t size() const noexcept;
  /// Records accepted by tryPush / tryPushWith since construction. @rt
  [[nodiscard]] std::uint64_t pushed() const noexcept { return tail_.load(std::memory_order_acquire); }
  /// Records refused because the ring was full. @rt
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }
  /// Records taken by the consumer since construction. @rt
  [[nodiscard]] std::uint64_t popped() const noexcept { return head_.load(std::memory_order_acquire); }

 private:
  static constexpr std::size_t kCacheLine = 64;

  std::unique_ptr<T[]> slots_;
  std::size_t mask_ = 0;
  // Producer-owned line: its index (published with release), its cached view of the consumer.
  alignas(kCacheLine) std::atomic<std::uint64_t> tail_{0};
  std::uint64_t head_cache_ = 0;
  std::atomic<std::uint64_t> dropped_{0};
  // Consumer-owned line.
  alignas(kCacheLine) std::atomic<std::uint64_t> head_{0};
  std::uint64_t tail_cache_ = 0;
};

// ---------------------------------------------------------------------------------------------

template <class T>
SpscRing<T>::SpscRing(std::size_t min_capacity) {
  if (min_capacity == 0 || min_capacity > (std::size_t{1} << 30)) {
    throw std::invalid_argument("SpscRing: capacity must be in 1 .. 2^30 records");
  }
  std::size_t capacity = 2;
  while (capacity < min_capacity) capacity <<= 1;
  slots_ = std::make_unique<T[]>(capacity);
  mask_ = capacity - 1;
}

template <class T>
bool SpscRing<T>::tryPush(const T& record) noexcept {
  return tryPushWith([&record](T& slot) noexcept { slot = record; });
}

template <class T>
template <class Fill>
bool SpscRing<T>::tryPushWith(Fill&& fill) noexcept(noexcept(fill(std::declval<T&>()))) {
  const std::uint64_t tail = tail_.load(std::memory_order_relaxed);
  if (tail - head_cache_ > mask_) {
    head_cache_ = head_.load(std::memory_order_acquire);
    if (tail - head_cache_ > mask_) {
      dropped_.store(dropped_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      return false;
    }
  }
  fill(slots_[tail & mask_]);
  tail_.store(tail + 1, std::memory_order_release);
  return true;
}

template <class T>
bool SpscRing<T>::tryPop(T& out) noexcept {
  return consumeAll([&out](const T& record) noexcept { out = record; }, 1) == 1;
}

template <class T>
template <class Visit>
std::size_t SpscRing<T>::consumeAll(Visit&& visit, std::size_t max_records) {
  const std::uint64_t head = head_.load(std::memory_order_relaxed);
  std::uint64_t available = tail_cache_ - head;
  if (available < max_records) {
    // The cached view of the producer may be old: look for records pushed since.
    tail_cache_ = tail_.load(std::memory_order_acquire);
    available = tail_cache_ - head;
  }
  const std::uint64_t n = available < max_records ? available : static_cast<std::uint64_t>(max_records);
  for (std::uint64_t i = 0; i < n; ++i) visit(static_cast<const T&>(slots_[(head + i) & mask_]));
  if (n > 0) head_.store(head + n, std::memory_order_release);
  return static_cast<std::size_t>(n);
}

template <class T>
std::size_t SpscRing<T>::size() const noexcept {
  const std::uint64_t head = head_.load(std::memory_order_acquire);
  const std::uint64_t tail = tail_.load(std::memory_order_acquire);
  return tail >= head ? static_cast<std::size_t>(tail - head) : 0;
}

}  // namespace fullarm::hil
