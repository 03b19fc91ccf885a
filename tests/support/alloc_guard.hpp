#pragma once
/// @file
/// Heap-allocation guard for tests of @rt code.
///
/// Counts every heap allocation made on the current thread while a guard is alive: operator
/// new (all forms) is replaced, and malloc/calloc/realloc/aligned_alloc/posix_memalign/memalign
/// are wrapped at link time (`-Wl,--wrap=...`, set by the fullarm_test_support target), which
/// also catches Eigen's direct std::malloc calls. The wrapping forwards to the real functions,
/// so it composes with AddressSanitizer.
///
///   fullarm::testing::AllocationGuard guard;
///   computeForwardKinematics(model, data, q);
///   EXPECT_EQ(guard.allocations(), 0u);
///
/// or simply EXPECT_NO_HEAP_ALLOCATION(statement);

#include <gtest/gtest.h>

#include <cstddef>

namespace fullarm::testing {

/// While alive, counts heap allocations made by this thread. Guards nest.
class AllocationGuard {
 public:
  AllocationGuard() noexcept;
  ~AllocationGuard();
  AllocationGuard(const AllocationGuard&) = delete;
  AllocationGuard& operator=(const AllocationGuard&) = delete;

  /// Allocations counted since this guard was made.
  [[nodiscard]] std::size_t allocations() const noexcept;
  /// Bytes requested since this guard was made.
  [[nodiscard]] std::size_t bytes() const noexcept;

 private:
  std::size_t start_count_;
  std::size_t start_bytes_;
};

/// True when the malloc-family wrappers are linked in (false would make the guard blind to
/// Eigen's allocations; tests assert it).
[[nodiscard]] bool mallocWrappersActive() noexcept;

}  // namespace fullarm::testing

/// Fails the test if `statement` allocates on the heap; prints the count and bytes.
#define EXPECT_NO_HEAP_ALLOCATION(statement)                                                                 \
  do {                                                                                                       \
    std::size_t fullarm_alloc_count_ = 0;                                                                    \
    std::size_t fullarm_alloc_bytes_ = 0;                                                                    \
    {                                                                                                        \
      ::fullarm::testing::AllocationGuard fullarm_alloc_guard_;                                              \
      statement;                                                                                             \
      fullarm_alloc_count_ = fullarm_alloc_guard_.allocations();                                             \
      fullarm_alloc_bytes_ = fullarm_alloc_guard_.bytes();                                                   \
    }                                                                                                        \
    EXPECT_EQ(fullarm_alloc_count_, 0u) << #statement << " allocated " << fullarm_alloc_count_ << " times (" \
                                        << fullarm_alloc_bytes_ << " bytes)";                                \
  } while (false)
