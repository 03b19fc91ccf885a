// The seeded streams against published reference values (SplitMix64, FNV-1a) and the
// properties the Monte-Carlo callers rely on (uniformity, range, independence of the key).
#include "fullarm/core/random.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <set>
#include <vector>

#include "alloc_guard.hpp"

namespace fullarm::core {
namespace {

// Reference output of splitmix64.c (Vigna) for the seed 1234567.
TEST(SplitMix64, MatchesTheReferenceImplementationsFirstOutputs) {
  std::uint64_t state = 1234567;
  EXPECT_EQ(splitMix64(state), 6457827717110365317ULL);
  EXPECT_EQ(splitMix64(state), 3203168211198807973ULL);
  EXPECT_EQ(splitMix64(state), 9817491932198370423ULL);
}

// The FNV-1a test vectors of the algorithm's authors (32-bit).
TEST(Fnv1a32, MatchesThePublishedTestVectors) {
  EXPECT_EQ(fnv1a32(""), 0x811c9dc5u);
  EXPECT_EQ(fnv1a32("a"), 0xe40c292cu);
  EXPECT_EQ(fnv1a32("foobar"), 0xbf9cf968u);
  static_assert(fnv1a32("a") == 0xe40c292cu, "usable at compile time");
  EXPECT_GE(nameSlot("R_SFE"), 0);
  EXPECT_EQ(nameSlot("R_SFE"), static_cast<int>(fnv1a32("R_SFE") & 0x7fffffffu));
}

TEST(RandomStream, IsAFunctionOfSeedStreamAndIndexOnly) {
  RandomStream a(7, 11, 3);
  RandomStream b(7, 11, 3);
  for (int i = 0; i < 100; ++i) ASSERT_EQ(a.next(), b.next());
  // Changing any one of the three keys changes the draws.
  const std::uint64_t base = RandomStream(7, 11, 3).next();
  EXPECT_NE(RandomStream(8, 11, 3).next(), base);
  EXPECT_NE(RandomStream(7, 12, 3).next(), base);
  EXPECT_NE(RandomStream(7, 11, 4).next(), base);
}

// The mean and variance of U[0, 1) over 200,000 draws from many streams, within 5 standard
// errors of 1/2 and 1/12, and every draw inside [0, 1).
TEST(RandomStream, Uniform01HasTheMomentsOfAUniformVariable) {
  const int n = 200000;
  double sum = 0.0;
  double sum_sq = 0.0;
  for (int k = 0; k < n; ++k) {
    RandomStream s(1, static_cast<std::uint64_t>(k % 97), static_cast<std::uint64_t>(k / 97));
    const double u = s.uniform01();
    ASSERT_GE(u, 0.0);
    ASSERT_LT(u, 1.0);
    sum += u;
    sum_sq += u * u;
  }
  const double mean = sum / n;
  const double var = sum_sq / n - mean * mean;
  EXPECT_NEAR(mean, 0.5, 5.0 * std::sqrt(1.0 / 12.0 / n));
  // Var of (u - 1/2)^2 is 1/180; the sample variance's standard error is about sqrt(1/180/n).
  EXPECT_NEAR(var, 1.0 / 12.0, 5.0 * std::sqrt(1.0 / 180.0 / n));
}

TEST(RandomStream, UniformIntCoversItsClosedRangeEvenly) {
  std::vector<int> counts(4, 0);
  const int n = 40000;
  for (int k = 0; k < n; ++k) {
    RandomStream s(3, 5, static_cast<std::uint64_t>(k));
    const int v = s.uniformInt(1, 4);
    ASSERT_GE(v, 1);
    ASSERT_LE(v, 4);
    ++counts[static_cast<std::size_t>(v - 1)];
  }
  // Binomial(n, 1/4): standard deviation sqrt(n 3/16) = 86.6.
  for (int c : counts) EXPECT_NEAR(c, n / 4, 5 * 87);
  RandomStream s(1, 1, 1);
  EXPECT_EQ(s.uniformInt(2, 2), 2);
  EXPECT_EQ(s.uniformInt(5, 3), 5);
  EXPECT_EQ(s.uniform(2.5, 2.5), 2.5);
}

TEST(RandomStream, DrawsWithoutAllocating) {
  double sum = 0.0;
  EXPECT_NO_HEAP_ALLOCATION({
    RandomStream s(1, 2, 3);
    for (int i = 0; i < 1000; ++i) sum += s.uniform(-1.0, 1.0);
  });
  EXPECT_TRUE(std::isfinite(sum));
}

}  // namespace
}  // namespace fullarm::core
