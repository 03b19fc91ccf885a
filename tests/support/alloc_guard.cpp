#include "alloc_guard.hpp"

#include <cstdlib>
#include <new>

namespace {

thread_local int t_depth = 0;
thread_local std::size_t t_count = 0;
thread_local std::size_t t_bytes = 0;
thread_local bool t_wrapper_seen = false;

inline void record(std::size_t bytes) noexcept {
  if (t_depth > 0) {
    ++t_count;
    t_bytes += bytes;
  }
}

}  // namespace

// Link-time wrappers (see -Wl,--wrap in tests/CMakeLists.txt).
extern "C" {
void* __real_malloc(std::size_t size);
void* __real_calloc(std::size_t n, std::size_t size);
void* __real_realloc(void* p, std::size_t size);
void* __real_aligned_alloc(std::size_t alignment, std::size_t size);
int __real_posix_memalign(void** out, std::size_t alignment, std::size_t size);
void* __real_memalign(std::size_t alignment, std::size_t size);

void* __wrap_malloc(std::size_t size) {
  t_wrapper_seen = true;
  record(size);
  return __real_malloc(size);
}
void* __wrap_calloc(std::size_t n, std::size_t size) {
  record(n * size);
  return __real_calloc(n, size);
}
void* __wrap_realloc(void* p, std::size_t size) {
  record(size);
  return __real_realloc(p, size);
}
void* __wrap_aligned_alloc(std::size_t alignment, std::size_t size) {
  record(size);
  return __real_aligned_alloc(alignment, size);
}
int __wrap_posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  record(size);
  return __real_posix_memalign(out, alignment, size);
}
void* __wrap_memalign(std::size_t alignment, std::size_t size) {
  record(size);
  return __real_memalign(alignment, size);
}
}

// Replaced operator new: libstdc++'s own operator new calls malloc inside the shared library,
// where the link-time wrapper does not reach, so count here.
namespace {
void* allocate(std::size_t size) {
  record(size);
  if (size == 0) size = 1;
  if (void* p = __real_malloc(size)) return p;
  throw std::bad_alloc();
}
void* allocateAligned(std::size_t size, std::align_val_t alignment) {
  record(size);
  void* p = nullptr;
  const std::size_t a =
      static_cast<std::size_t>(alignment) < sizeof(void*) ? sizeof(void*) : static_cast<std::size_t>(alignment);
  if (__real_posix_memalign(&p, a, size == 0 ? a : size) != 0) throw std::bad_alloc();
  return p;
}
}  // namespace

void* operator new(std::size_t size) {
  return allocate(size);
}
void* operator new[](std::size_t size) {
  return allocate(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return allocate(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t al) {
  return allocateAligned(size, al);
}
void* operator new[](std::size_t size, std::align_val_t al) {
  return allocateAligned(size, al);
}
void operator delete(void* p) noexcept {
  std::free(p);
}
void operator delete[](void* p) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete(void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept {
  std::free(p);
}

namespace fullarm::testing {

AllocationGuard::AllocationGuard() noexcept : start_count_(t_count), start_bytes_(t_bytes) {
  ++t_depth;
}
AllocationGuard::~AllocationGuard() {
  --t_depth;
}
std::size_t AllocationGuard::allocations() const noexcept {
  return t_count - start_count_;
}
std::size_t AllocationGuard::bytes() const noexcept {
  return t_bytes - start_bytes_;
}

bool mallocWrappersActive() noexcept {
  // Call through a volatile pointer and read the flag through a volatile access: GCC assumes
  // the malloc builtin touches no other memory and would fold the probe to `false`.
  static void* (*volatile malloc_fn)(std::size_t) = &std::malloc;
  t_wrapper_seen = false;
  void* p = malloc_fn(16);
  std::free(p);
  return *static_cast<volatile bool*>(&t_wrapper_seen);
}

}  // namespace fullarm::testing
