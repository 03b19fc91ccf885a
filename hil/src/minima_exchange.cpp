#include "fullarm/hil/minima_exchange.hpp"

namespace fullarm::hil {

MinimaExchange::MinimaExchange() : slots_(std::make_unique<MinimaSetRecord[]>(3)) {}

void MinimaExchange::publish() noexcept {
  // Release: the reader that acquires this index sees every byte written into the slot.
  // Acquire: the slot handed back was last read by the reader before it released it.
  const std::uint8_t previous =
      middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
  back_ = static_cast<std::uint8_t>(previous & kIndexMask);
  published_.store(published_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  if ((previous & kFresh) != 0) {
    overwritten_.store(overwritten_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  }
}

void MinimaExchange::publish(const MinimaSetRecord& set) noexcept {
  writeSlot() = set;
  publish();
}

const MinimaSetRecord* MinimaExchange::takeNewest() noexcept {
  if ((middle_.load(std::memory_order_relaxed) & kFresh) == 0) return nullptr;
  const std::uint8_t previous = middle_.exchange(front_, std::memory_order_acq_rel);
  front_ = static_cast<std::uint8_t>(previous & kIndexMask);
  taken_any_ = true;
  taken_.store(taken_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  return &slots_[front_];
}

}  // namespace fullarm::hil
