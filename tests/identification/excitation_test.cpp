// Excitation signals against brute force: zero-crossing counts of the analytic chirp phase,
// m-sequence properties (period, balance, two-valued autocorrelation), the DFT of a multisine.

#include "fullarm/identification/excitation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <stdexcept>

namespace fullarm::identification {
namespace {

constexpr double kT = 1.0e-3;

int signChanges(const std::vector<double>& v, std::size_t from, std::size_t to) {
  int n = 0;
  for (std::size_t k = from + 1; k < to; ++k) {
    if ((v[k - 1] < 0.0) != (v[k] < 0.0)) ++n;
  }
  return n;
}

TEST(ExcitationTest, LinearChirpCrossesZeroTwicePerCycleOfItsPhase) {
  const double f0 = 0.5, f1 = 40.0, dur = 10.0;
  const SampledSignal s = linearChirp(2.0, f0, f1, dur, kT);
  ASSERT_EQ(s.value_v.size(), 10000u);
  // Cycles of the phase over [0, T]: f0 T + (f1 - f0) T / 2.
  const double cycles = f0 * dur + 0.5 * (f1 - f0) * dur;
  EXPECT_NEAR(signChanges(s.value_v, 0, s.value_v.size()), 2.0 * cycles, 2.0);
  // Local frequency over the last second: f(t) = f0 + (f1 - f0) t / T, mean over [9, 10] s.
  const double local_cycles = f0 + (f1 - f0) * 9.5 / dur;
  EXPECT_NEAR(signChanges(s.value_v, 9000, 10000), 2.0 * local_cycles, 2.0);
  double peak = 0.0;
  for (double v : s.value_v) peak = std::max(peak, std::abs(v));
  EXPECT_LE(peak, 2.0);
  EXPECT_GT(peak, 1.99);
}

TEST(ExcitationTest, LogChirpSpendsEqualTimePerDecade) {
  const double f0 = 1.0, f1 = 100.0, dur = 20.0;
  const SampledSignal s = logChirp(1.0, f0, f1, dur, kT);
  // Instantaneous frequency f0 (f1/f0)^(t/T): 10 Hz at t = 10 s; count over 9.5..10.5 s.
  // Cycles in [a, b]: f0 T (r^(b/T) - r^(a/T)) / ln r.
  const double r = f1 / f0;
  const double cycles = f0 * dur * (std::pow(r, 10.5 / dur) - std::pow(r, 9.5 / dur)) / std::log(r);
  EXPECT_NEAR(signChanges(s.value_v, 9500, 10500), 2.0 * cycles, 2.0);
  const double first_decade = f0 * dur * (10.0 - 1.0) / std::log(r);
  const double second_decade = f0 * dur * (100.0 - 10.0) / std::log(r);
  EXPECT_NEAR(signChanges(s.value_v, 0, 10000), 2.0 * first_decade, 2.0);
  EXPECT_NEAR(signChanges(s.value_v, 10000, 20000), 2.0 * second_decade, 2.0);
}

TEST(ExcitationTest, ChirpsRejectBandsAboveNyquistAndBadArguments) {
  EXPECT_THROW((void)linearChirp(1.0, 1.0, 600.0, 1.0, kT), std::invalid_argument);
  EXPECT_THROW((void)linearChirp(1.0, 1.0, 10.0, 0.0, kT), std::invalid_argument);
  EXPECT_THROW((void)linearChirp(1.0, 1.0, 10.0, 1.0, -kT), std::invalid_argument);
  EXPECT_THROW((void)logChirp(1.0, 10.0, 10.0, 1.0, kT), std::invalid_argument);
  EXPECT_THROW((void)logChirp(1.0, 0.0, 10.0, 1.0, kT), std::invalid_argument);
  EXPECT_THROW((void)logChirp(1.0, 1.0, std::nan(""), 1.0, kT), std::invalid_argument);
}

TEST(ExcitationTest, PrbsIsAMaximumLengthSequenceForEveryOrder) {
  for (int order = 2; order <= 20; ++order) {
    const SampledSignal s = prbs(1.0, order, 1, 2, kT);
    const std::size_t length = (std::size_t{1} << order) - 1;
    ASSERT_EQ(s.value_v.size(), 2 * length) << "order " << order;
    int ones = 0;
    for (std::size_t k = 0; k < length; ++k) {
      ASSERT_EQ(s.value_v[k], s.value_v[k + length]) << "order " << order << " not periodic at " << k;
      if (s.value_v[k] > 0.0) ++ones;
    }
    // Balance: an m-sequence of period 2^n - 1 holds 2^(n-1) ones.
    EXPECT_EQ(ones, 1 << (order - 1)) << "order " << order;
    if (order <= 11) {
      // Two-valued circular autocorrelation: L at lag 0, -1 at every other lag (only an
      // m-sequence has it, so no shorter period hides inside the period).
      for (std::size_t lag = 1; lag < length; ++lag) {
        double acc = 0.0;
        for (std::size_t k = 0; k < length; ++k) acc += s.value_v[k] * s.value_v[(k + lag) % length];
        ASSERT_EQ(acc, -1.0) << "order " << order << " lag " << lag;
      }
    }
  }
}

TEST(ExcitationTest, PrbsClockPeriodHoldsEachBitAndFollowsTheBand) {
  const SampledSignal s = prbs(0.5, 5, 4, 1, kT);
  ASSERT_EQ(s.value_v.size(), 31u * 4u);
  for (std::size_t k = 0; k < s.value_v.size(); ++k) {
    EXPECT_EQ(std::abs(s.value_v[k]), 0.5);
    EXPECT_EQ(s.value_v[k], s.value_v[k - k % 4]);
  }
  EXPECT_EQ(prbsClockSamplesForBand(500.0, kT), 1);
  EXPECT_EQ(prbsClockSamplesForBand(50.0, kT), 10);
  EXPECT_EQ(prbsClockSamplesForBand(1000.0, kT), 1);
  EXPECT_THROW((void)prbs(1.0, 1, 1, 1, kT), std::invalid_argument);
  EXPECT_THROW((void)prbs(1.0, 25, 1, 1, kT), std::invalid_argument);
  EXPECT_THROW((void)prbs(1.0, 8, 0, 1, kT), std::invalid_argument);
  EXPECT_THROW((void)prbsClockSamplesForBand(0.0, kT), std::invalid_argument);
}

TEST(ExcitationTest, SchroederMultisineHasFlatSpectrumOnItsHarmonicsAndLowCrestFactor) {
  const Multisine m = schroederMultisine(1.5, 1.0, 60.0, 1.0, 3, kT);
  ASSERT_EQ(m.samples_per_period, 1000);
  EXPECT_DOUBLE_EQ(m.fundamental_hz, 1.0);
  ASSERT_EQ(m.harmonics.size(), 60u);
  EXPECT_EQ(m.harmonics.front(), 1);
  EXPECT_EQ(m.harmonics.back(), 60);
  ASSERT_EQ(m.signal.value_v.size(), 3000u);
  // Brute-force DFT of one period: equal magnitude on the excited lines, nothing elsewhere.
  const int n = m.samples_per_period;
  double reference = -1.0;
  for (int k = 0; k <= n / 2; ++k) {
    std::complex<double> x{};
    for (int i = 0; i < n; ++i) {
      x += m.signal.value_v[static_cast<std::size_t>(i)] * std::polar(1.0, -2.0 * std::numbers::pi * k * i / n);
    }
    const bool excited = k >= 1 && k <= 60;
    if (excited) {
      if (reference < 0.0) reference = std::abs(x);
      EXPECT_NEAR(std::abs(x), reference, 1e-9 * n) << "harmonic " << k;
    } else {
      EXPECT_LT(std::abs(x), 1e-9 * n) << "line " << k;
    }
  }
  // Periodic, peak at the amplitude, crest factor as computed by brute force and low
  // (Schroeder phases on consecutive harmonics: about 1.5-2; random phases give ~3-4).
  double peak = 0.0, sum_sq = 0.0;
  for (int i = 0; i < n; ++i) {
    const double v = m.signal.value_v[static_cast<std::size_t>(i)];
    EXPECT_EQ(v, m.signal.value_v[static_cast<std::size_t>(i + 2 * n)]);
    peak = std::max(peak, std::abs(v));
    sum_sq += v * v;
  }
  EXPECT_NEAR(peak, 1.5, 1e-12);
  EXPECT_NEAR(m.crest_factor, peak / std::sqrt(sum_sq / n), 1e-12);
  EXPECT_LT(m.crest_factor, 2.0);
  EXPECT_GT(m.crest_factor, std::sqrt(2.0));  // no sum of sines beats one sine
}

TEST(ExcitationTest, MultisineBandStartsAtTheFirstHarmonicAboveTheLowEdge) {
  const Multisine m = schroederMultisine(1.0, 2.5, 10.0, 2.0, 1, kT);  // f0 = 0.5 Hz
  ASSERT_FALSE(m.harmonics.empty());
  EXPECT_EQ(m.harmonics.front(), 5);
  EXPECT_EQ(m.harmonics.back(), 20);
  EXPECT_THROW((void)schroederMultisine(1.0, 0.2, 0.4, 1.0, 1, kT), std::invalid_argument);
  EXPECT_THROW((void)schroederMultisine(1.0, 1.0, 700.0, 1.0, 1, kT), std::invalid_argument);
  EXPECT_THROW((void)schroederMultisine(1.0, 1.0, 10.0, 1.0, 0, kT), std::invalid_argument);
}

TEST(ExcitationTest, StepsHoldEachLevel) {
  const SampledSignal s = stepSequence({0.0, 1.0, -1.0}, 0.25, kT);
  ASSERT_EQ(s.value_v.size(), 750u);
  EXPECT_EQ(s.value_v[0], 0.0);
  EXPECT_EQ(s.value_v[249], 0.0);
  EXPECT_EQ(s.value_v[250], 1.0);
  EXPECT_EQ(s.value_v[749], -1.0);
  EXPECT_DOUBLE_EQ(s.time_s[500], 0.5);
  EXPECT_THROW((void)stepSequence({}, 0.25, kT), std::invalid_argument);
  EXPECT_THROW((void)stepSequence({1.0}, 0.0, kT), std::invalid_argument);
}

TEST(ExcitationTest, CrestFactorOfASineIsRootTwo) {
  std::vector<double> v(1000);
  for (std::size_t k = 0; k < v.size(); ++k)
    v[k] = std::sin(2.0 * std::numbers::pi * 7.0 * static_cast<double>(k) / 1000.0 + 0.3);
  const double peak_ratio = crestFactor(v);
  EXPECT_NEAR(peak_ratio, std::sqrt(2.0), 1e-3);
  EXPECT_EQ(crestFactor({}), 0.0);
  EXPECT_EQ(crestFactor({0.0, 0.0}), 0.0);
}

}  // namespace
}  // namespace fullarm::identification
