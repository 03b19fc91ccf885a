#pragma once
/// @file
/// Counter-based seeded random streams and the name hash that keys them. A stream is fixed by
/// (seed, stream, index) alone, so a Monte-Carlo sample is the same whichever thread, process or
/// order draws it, and a joint's draws do not depend on which other joints are in the run.

#include <cstdint>
#include <string_view>

namespace fullarm::core {

/// 32-bit FNV-1a hash of `text` (Fowler, Noll and Vo): a stable key for a name (a joint's stream
/// does not depend on its place in a file). @rt
[[nodiscard]] constexpr std::uint32_t fnv1a32(std::string_view text) noexcept {
  std::uint32_t h = 2166136261u;
  for (const char c : text) {
    h ^= static_cast<unsigned char>(c);
    h *= 16777619u;
  }
  return h;
}

/// fnv1a32(name) as a non-negative stream key (its top bit cleared). @rt
[[nodiscard]] constexpr int nameSlot(std::string_view name) noexcept {
  return static_cast<int>(fnv1a32(name) & 0x7fffffffu);
}

/// One step of SplitMix64 (Steele, Lea and Flood, "Fast splittable pseudorandom number
/// generators", OOPSLA 2014): advances `state` and returns the next output. @rt
[[nodiscard]] constexpr std::uint64_t splitMix64(std::uint64_t& state) noexcept {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

/// The draws of one (seed, stream, index): SplitMix64 started from the seed mixed with the
/// stream key and the index. Cheap to construct; construct one per sample. @rt throughout.
class RandomStream {
 public:
  /// @param seed   the run's seed
  /// @param stream which stream (for example nameSlot(joint name), or a salted slot)
  /// @param index  which sample of that stream (>= 0)
  constexpr RandomStream(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) noexcept : state_(seed) {
    (void)splitMix64(state_);
    state_ ^= 0x632be59bd9b4e019ULL * (stream + 1);
    (void)splitMix64(state_);
    state_ ^= 0x8cb92ba72f3d8dd7ULL * (index + 1);
  }

  /// The next 64 random bits.
  [[nodiscard]] constexpr std::uint64_t next() noexcept { return splitMix64(state_); }

  /// Uniform on [0, 1) with 53 random bits.
  [[nodiscard]] constexpr double uniform01() noexcept { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

  /// Uniform on [min, max) (min when min == max).
  [[nodiscard]] constexpr double uniform(double min, double max) noexcept { return min + (max - min) * uniform01(); }

  /// Uniform integer in [min, max] (min when max < min).
  [[nodiscard]] constexpr int uniformInt(int min, int max) noexcept {
    if (max <= min) return min;
    const int span = max - min + 1;
    const int k = min + static_cast<int>(uniform01() * span);
    return k > max ? max : k;
  }

 private:
  std::uint64_t state_;
};

}  // namespace fullarm::core
