#pragma once
/// @file
/// MinimaExchange: the fixed-capacity hand-off through which the global search gives the tick
/// its newest set of minima (DTS paper section 3.2.1: the tick keeps descending its old minima
/// until a new set arrives).
///
/// One writer (the global search) publishes whole sets; one reader (the tick) takes the newest
/// complete set, or learns that nothing new arrived. Neither side ever waits for the other and
/// a set is never torn: it is a double buffer with one spare slot (a triple buffer). The writer
/// fills a slot the reader cannot see, then swaps it with the shared middle slot in one atomic
/// exchange; the reader swaps its own slot with the middle one only when the middle holds a set
/// it has not taken. A set the writer replaces before the reader took it is never seen (counted
/// in `overwritten()`): the tick always gets the newest set, never a backlog. Memory is
/// allocated once, in the constructor.
///
///   // global-search thread                   // tick
///   MinimaSetRecord& s = ex.writeSlot();      if (const MinimaSetRecord* s = ex.takeNewest()) {
///   s.set_id = ...; fillMinima(found, s);       adopt(*s);  // valid until the next takeNewest
///   ex.publish();                             }

#include <atomic>
#include <cstdint>
#include <memory>

#include "fullarm/hil/log_records.hpp"

namespace fullarm::hil {

/// Single-writer/single-reader newest-value exchange of minima sets (a triple buffer).
class MinimaExchange {
 public:
  /// Allocates the three slots (each holds kMaxMinimaPerSet minima).
  MinimaExchange();
  MinimaExchange(const MinimaExchange&) = delete;
  MinimaExchange& operator=(const MinimaExchange&) = delete;

  // --- writer side (one thread) --------------------------------------------------------------

  /// The slot the writer fills next; the reader cannot see it until publish(). Its contents on
  /// entry are an older set's: the writer sets every field it means to send. @rt
  [[nodiscard]] MinimaSetRecord& writeSlot() noexcept { return slots_[back_]; }
  /// Makes the write slot the newest set and hands the writer another slot. @rt
  void publish() noexcept;
  /// Copies `set` into the write slot and publishes it. @rt
  void publish(const MinimaSetRecord& set) noexcept;

  // --- reader side (one thread) --------------------------------------------------------------

  /// The newest set published since the last call, or nullptr if none was. The set stays
  /// valid and unchanged until the next takeNewest() on this exchange. @rt
  [[nodiscard]] const MinimaSetRecord* takeNewest() noexcept;
  /// The set the last successful takeNewest() returned, or nullptr before the first. @rt
  [[nodiscard]] const MinimaSetRecord* current() const noexcept { return taken_any_ ? &slots_[front_] : nullptr; }

  // --- counters (any thread) -----------------------------------------------------------------

  /// Sets published. @rt
  [[nodiscard]] std::uint64_t published() const noexcept { return published_.load(std::memory_order_relaxed); }
  /// Sets taken by the reader. @rt
  [[nodiscard]] std::uint64_t taken() const noexcept { return taken_.load(std::memory_order_relaxed); }
  /// Sets replaced by a newer one before the reader took them. @rt
  [[nodiscard]] std::uint64_t overwritten() const noexcept { return overwritten_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::uint8_t kIndexMask = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;  ///< the middle slot holds a set not yet taken

  std::unique_ptr<MinimaSetRecord[]> slots_;
  std::uint8_t back_ = 0;                    ///< writer's slot (writer thread only)
  alignas(64) std::atomic<std::uint8_t> middle_{1};  ///< shared slot index | kFresh
  alignas(64) std::uint8_t front_ = 2;       ///< reader's slot (reader thread only)
  bool taken_any_ = false;                   ///< reader thread only
  std::atomic<std::uint64_t> published_{0};
  std::atomic<std::uint64_t> taken_{0};
  std::atomic<std::uint64_t> overwritten_{0};
};

}  // namespace fullarm::hil
