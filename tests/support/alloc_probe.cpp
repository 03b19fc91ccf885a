// A shared library that allocates, for the allocation guard's own test: the guard must see
// allocations made inside shared libraries, not only in the test program.
#include <cstdlib>
#include <string>

extern "C" {

__attribute__((visibility("default"))) void fullarmProbeMallocAndFree(std::size_t bytes) {
  void* volatile p = std::malloc(bytes);
  std::free(p);
}

__attribute__((visibility("default"))) std::size_t fullarmProbeNewString(std::size_t length) {
  auto* s = new std::string(length, 'x');
  const std::size_t n = s->size();
  delete s;
  return n;
}
}
