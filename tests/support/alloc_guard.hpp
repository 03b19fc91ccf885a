#pragma once
/// @file
/// Heap-allocation guard for tests of @rt code.
///
/// Counts every heap allocation the current thread makes while a guard is alive, from any code:
/// the test program itself, the fullarm libraries, and the shared libraries they call (CVODES,
/// yaml-cpp, libstdc++, ...). The test executable defines the C allocation functions (malloc,
/// calloc, realloc, free, aligned_alloc, posix_memalign, memalign, valloc, pvalloc) and every
/// form of operator new/delete; the dynamic linker resolves every library's calls to these
/// definitions first, and they forward to the next definition in the lookup order, found with
/// dlsym(RTLD_NEXT). Under AddressSanitizer or ThreadSanitizer, whose allocator already serves
/// every library, the guard counts through the sanitizer's allocation hooks instead
/// (__sanitizer_install_malloc_and_free_hooks).
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

/// True when this program's allocation functions are the ones every library calls (false would
/// make the guard blind to allocations in shared libraries; tests assert it).
[[nodiscard]] bool allocatorInterposed() noexcept;

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
