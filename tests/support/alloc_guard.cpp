#include "alloc_guard.hpp"

#include <dlfcn.h>

#include <atomic>
#include <cerrno>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <new>

namespace {

// Per-thread counters: plain thread_local scalars of the executable (static TLS, so reading
// them never allocates, even from inside malloc).
thread_local int t_depth = 0;
thread_local std::size_t t_count = 0;
thread_local std::size_t t_bytes = 0;

inline void record(std::size_t bytes) noexcept {
  if (t_depth > 0) {
    ++t_count;
    t_bytes += bytes;
  }
}

}  // namespace

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
// Under AddressSanitizer or ThreadSanitizer the sanitizer's allocator serves every library, and
// its instrumented code cannot run before the sanitizer starts: count through the allocator's
// own hooks instead of defining the allocation functions.
extern "C" int __sanitizer_install_malloc_and_free_hooks(void (*malloc_hook)(const volatile void*, std::size_t),
                                                         void (*free_hook)(const volatile void*));
namespace {
void mallocHook(const volatile void* /*p*/, std::size_t size) {
  record(size);
}
void freeHook(const volatile void* /*p*/) {}
const bool g_hooks_installed = __sanitizer_install_malloc_and_free_hooks(&mallocHook, &freeHook) != 0;
}  // namespace

namespace fullarm::testing {
bool allocatorInterposed() noexcept {
  return g_hooks_installed;
}
}  // namespace fullarm::testing

#else
namespace {

// The next definitions of the allocation functions (glibc's, or AddressSanitizer's).
using MallocFn = void* (*)(std::size_t);
using CallocFn = void* (*)(std::size_t, std::size_t);
using ReallocFn = void* (*)(void*, std::size_t);
using FreeFn = void (*)(void*);
using AlignedAllocFn = void* (*)(std::size_t, std::size_t);
using PosixMemalignFn = int (*)(void**, std::size_t, std::size_t);

struct Next {
  MallocFn malloc = nullptr;
  CallocFn calloc = nullptr;
  ReallocFn realloc = nullptr;
  FreeFn free = nullptr;
  AlignedAllocFn aligned_alloc = nullptr;
  PosixMemalignFn posix_memalign = nullptr;
  AlignedAllocFn memalign = nullptr;
  MallocFn valloc = nullptr;
  MallocFn pvalloc = nullptr;
};

Next g_next;
std::atomic<int> g_resolving{0};

// dlsym itself may allocate (glibc's dlerror buffer) before the next malloc is known: such
// requests are served from this arena and never freed.
alignas(std::max_align_t) unsigned char g_arena[64 * 1024];
std::atomic<std::size_t> g_arena_used{0};

bool inArena(const void* p) noexcept {
  const auto* c = static_cast<const unsigned char*>(p);
  return c >= g_arena && c < g_arena + sizeof(g_arena);
}

void* arenaAllocate(std::size_t size, std::size_t alignment = alignof(std::max_align_t)) noexcept {
  std::size_t used = g_arena_used.load();
  for (;;) {
    const std::size_t start = (used + alignment - 1) / alignment * alignment;
    if (start + size > sizeof(g_arena)) return nullptr;
    if (g_arena_used.compare_exchange_weak(used, start + size)) {
      std::memset(g_arena + start, 0, size);
      return g_arena + start;
    }
  }
}

template <typename F>
F lookup(const char* name) noexcept {
  return reinterpret_cast<F>(dlsym(RTLD_NEXT, name));
}

void resolve() noexcept {
  if (g_next.free != nullptr) return;
  g_resolving.fetch_add(1);
  g_next.malloc = lookup<MallocFn>("malloc");
  g_next.calloc = lookup<CallocFn>("calloc");
  g_next.realloc = lookup<ReallocFn>("realloc");
  g_next.aligned_alloc = lookup<AlignedAllocFn>("aligned_alloc");
  g_next.posix_memalign = lookup<PosixMemalignFn>("posix_memalign");
  g_next.memalign = lookup<AlignedAllocFn>("memalign");
  g_next.valloc = lookup<MallocFn>("valloc");
  g_next.pvalloc = lookup<MallocFn>("pvalloc");
  g_next.free = lookup<FreeFn>("free");
  g_resolving.fetch_sub(1);
  if (g_next.malloc == nullptr || g_next.free == nullptr) std::abort();
}

// True while the next functions are being looked up: serve from the arena.
inline bool bootstrapping() noexcept {
  if (g_next.free != nullptr) return false;
  if (g_resolving.load() > 0) return true;
  resolve();
  return false;
}

void* allocate(std::size_t size) {
  if (size == 0) size = 1;
  if (void* p = std::malloc(size)) return p;
  throw std::bad_alloc();
}

void* allocateAligned(std::size_t size, std::align_val_t alignment) {
  void* p = nullptr;
  const std::size_t a =
      static_cast<std::size_t>(alignment) < sizeof(void*) ? sizeof(void*) : static_cast<std::size_t>(alignment);
  if (posix_memalign(&p, a, size == 0 ? a : size) != 0) throw std::bad_alloc();
  return p;
}

}  // namespace

// The C allocation functions of the test program: every library's calls land here.
extern "C" {

void* malloc(std::size_t size) {
  if (bootstrapping()) return arenaAllocate(size);
  record(size);
  return g_next.malloc(size);
}

void* calloc(std::size_t n, std::size_t size) {
  if (bootstrapping()) return arenaAllocate(n * size);
  record(n * size);
  return g_next.calloc(n, size);
}

void* realloc(void* p, std::size_t size) {
  if (bootstrapping() || inArena(p)) {
    // Only during start-up: copy out of the arena (its block size is unknown; copy what fits).
    void* q = bootstrapping() ? arenaAllocate(size) : malloc(size);
    if (q != nullptr && p != nullptr) {
      const std::size_t room = static_cast<std::size_t>(g_arena + sizeof(g_arena) - static_cast<unsigned char*>(p));
      std::memcpy(q, p, size < room ? size : room);
    }
    return q;
  }
  record(size);
  return g_next.realloc(p, size);
}

void free(void* p) {
  if (p == nullptr || inArena(p)) return;
  if (g_next.free == nullptr) resolve();
  g_next.free(p);
}

void* aligned_alloc(std::size_t alignment, std::size_t size) {
  if (bootstrapping()) return arenaAllocate(size, alignment);
  record(size);
  return g_next.aligned_alloc(alignment, size);
}

int posix_memalign(void** out, std::size_t alignment, std::size_t size) {
  if (bootstrapping()) {
    *out = arenaAllocate(size, alignment);
    return *out != nullptr ? 0 : ENOMEM;
  }
  record(size);
  return g_next.posix_memalign(out, alignment, size);
}

void* memalign(std::size_t alignment, std::size_t size) {
  if (bootstrapping()) return arenaAllocate(size, alignment);
  record(size);
  return g_next.memalign(alignment, size);
}

void* valloc(std::size_t size) {
  if (bootstrapping()) return arenaAllocate(size, 4096);
  record(size);
  return g_next.valloc(size);
}

void* pvalloc(std::size_t size) {
  if (bootstrapping()) return arenaAllocate(size, 4096);
  record(size);
  return g_next.pvalloc(size);
}

}  // extern "C"

// operator new/delete of every form, on the functions above (so each counts once).
void* operator new(std::size_t size) {
  return allocate(size);
}
void* operator new[](std::size_t size) {
  return allocate(size);
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  return std::malloc(size == 0 ? 1 : size);
}
void* operator new(std::size_t size, std::align_val_t al) {
  return allocateAligned(size, al);
}
void* operator new[](std::size_t size, std::align_val_t al) {
  return allocateAligned(size, al);
}
void* operator new(std::size_t size, std::align_val_t al, const std::nothrow_t&) noexcept {
  try {
    return allocateAligned(size, al);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, std::align_val_t al, const std::nothrow_t&) noexcept {
  try {
    return allocateAligned(size, al);
  } catch (...) {
    return nullptr;
  }
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
void operator delete(void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept {
  std::free(p);
}

namespace fullarm::testing {

bool allocatorInterposed() noexcept {
  // Ask the dynamic linker which malloc a shared library would call: the global lookup from
  // the start (RTLD_DEFAULT) must find this program's definition.
  void* seen = dlsym(RTLD_DEFAULT, "malloc");
  return seen == reinterpret_cast<void*>(&malloc);
}

}  // namespace fullarm::testing
#endif

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

}  // namespace fullarm::testing
