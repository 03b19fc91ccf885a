// computeHistogramBins against a brute-force count over the returned edges.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numeric>
#include <random>

#include "fullarm/reports/charts.hpp"

namespace fullarm::reports {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
// Relative tolerance for edges computed through log10/pow.
constexpr double kEdgeRelTol = 1e-12;
constexpr unsigned kSeed = 20240301;

// Brute force: the number of samples in [edges[i], edges[i+1]), the last bin closed.
std::vector<std::size_t> bruteForceCounts(const std::vector<double>& samples, const std::vector<double>& edges) {
  std::vector<std::size_t> counts(edges.size() - 1, 0);
  for (const double sample : samples) {
    for (std::size_t i = 0; i + 1 < edges.size(); ++i) {
      const bool last = i + 2 == edges.size();
      if (sample >= edges[i] && (sample < edges[i + 1] || (last && sample == edges[i + 1]))) {
        ++counts[i];
        break;
      }
    }
  }
  return counts;
}

std::size_t total(const std::vector<std::size_t>& counts) {
  return std::accumulate(counts.begin(), counts.end(), std::size_t{0});
}

TEST(HistogramBins, LinearBinsMatchABruteForceCount) {
  std::mt19937 random(kSeed);
  std::normal_distribution<double> normal(2.0, 0.5);
  Histogram histogram;
  histogram.title = "Normal";
  histogram.bin_count = 20;
  histogram.series.push_back({"a", {}});
  histogram.series.push_back({"b", {}});
  for (int i = 0; i < 5000; ++i) {
    histogram.series[0].samples.push_back(normal(random));
  }
  for (int i = 0; i < 300; ++i) {
    histogram.series[1].samples.push_back(normal(random) + 1.0);
  }

  const HistogramBins bins = computeHistogramBins(histogram);

  ASSERT_EQ(bins.edges.size(), 21U);
  const auto [min_a, max_a] =
      std::minmax_element(histogram.series[0].samples.begin(), histogram.series[0].samples.end());
  const auto [min_b, max_b] =
      std::minmax_element(histogram.series[1].samples.begin(), histogram.series[1].samples.end());
  EXPECT_EQ(bins.edges.front(), std::min(*min_a, *min_b));
  EXPECT_EQ(bins.edges.back(), std::max(*max_a, *max_b));
  for (std::size_t s = 0; s < 2; ++s) {
    EXPECT_EQ(bins.counts[s], bruteForceCounts(histogram.series[s].samples, bins.edges)) << s;
    EXPECT_EQ(total(bins.counts[s]), histogram.series[s].samples.size());
    EXPECT_EQ(bins.missing[s], 0U);
    EXPECT_EQ(bins.out_of_range[s], 0U);
  }
}

TEST(HistogramBins, LogBinsAreGeometricAndMatchABruteForceCount) {
  std::mt19937 random(kSeed);
  std::lognormal_distribution<double> log_normal(-7.0, 1.0);  // loop jitter around 1 ms
  Histogram histogram;
  histogram.title = "Jitter";
  histogram.x_axis = {"Jitter", "s", true};
  histogram.bin_count = 12;
  histogram.series.push_back({"tick", {}});
  for (int i = 0; i < 2000; ++i) {
    histogram.series[0].samples.push_back(log_normal(random));
  }

  const HistogramBins bins = computeHistogramBins(histogram);

  ASSERT_EQ(bins.edges.size(), 13U);
  const double ratio = bins.edges[1] / bins.edges[0];
  for (std::size_t i = 1; i + 1 < bins.edges.size(); ++i) {
    EXPECT_NEAR(bins.edges[i + 1] / bins.edges[i], ratio, ratio * kEdgeRelTol) << i;
  }
  // Away from edge rounding, the count must match a direct count over the edges.
  const std::vector<std::size_t> expected = bruteForceCounts(histogram.series[0].samples, bins.edges);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    differing += expected[i] != bins.counts[0][i] ? 1 : 0;
  }
  EXPECT_EQ(differing, 0U);
  EXPECT_EQ(total(bins.counts[0]), 2000U);
}

TEST(HistogramBins, ExplicitRangeCountsSamplesOutsideAndNanSeparately) {
  Histogram histogram;
  histogram.title = "Range";
  histogram.bin_count = 4;
  histogram.range = std::array<double, 2>{0.0, 4.0};
  histogram.series.push_back({"s", {-1.0, 0.0, 0.5, 1.0, 3.99, 4.0, 4.01, kNan, kNan}});

  const HistogramBins bins = computeHistogramBins(histogram);

  EXPECT_EQ(bins.edges, (std::vector<double>{0.0, 1.0, 2.0, 3.0, 4.0}));
  EXPECT_EQ(bins.counts[0], (std::vector<std::size_t>{2, 1, 0, 2}));
  EXPECT_EQ(bins.out_of_range[0], 2U);
  EXPECT_EQ(bins.missing[0], 2U);
}

TEST(HistogramBins, AutomaticBinCountFollowsFreedmanDiaconis) {
  // 1000 uniform samples on [0, 1): IQR ~ 0.5, bin width 2 * 0.5 / 1000^(1/3) = 0.1, ~10 bins.
  std::mt19937 random(kSeed);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  Histogram histogram;
  histogram.title = "Uniform";
  histogram.series.push_back({"u", {}});
  for (int i = 0; i < 1000; ++i) {
    histogram.series[0].samples.push_back(uniform(random));
  }
  const std::size_t bin_count = computeHistogramBins(histogram).edges.size() - 1;
  EXPECT_GE(bin_count, 9U);
  EXPECT_LE(bin_count, 11U);
}

TEST(HistogramBins, ZeroSpreadFallsBackToSturges) {
  // IQR 0 with 9 samples: ceil(log2 9) + 1 = 5 bins.
  Histogram histogram;
  histogram.title = "Spike";
  histogram.series.push_back({"s", {0, 0, 0, 0, 0, 0, 0, 0, 1}});
  const HistogramBins bins = computeHistogramBins(histogram);
  EXPECT_EQ(bins.edges.size() - 1, 5U);
  EXPECT_EQ(bins.counts[0].front(), 8U);
  EXPECT_EQ(bins.counts[0].back(), 1U);
}

TEST(HistogramBins, EqualSamplesGetOneBinAroundTheValue) {
  Histogram histogram;
  histogram.title = "Constant";
  histogram.series.push_back({"s", {2.0, 2.0, 2.0}});
  const HistogramBins bins = computeHistogramBins(histogram);
  ASSERT_EQ(bins.edges.size(), 2U);
  EXPECT_LT(bins.edges[0], 2.0);
  EXPECT_GT(bins.edges[1], 2.0);
  EXPECT_EQ(bins.counts[0], (std::vector<std::size_t>{3}));
}

TEST(HistogramBins, NoSamplesGiveOneEmptyBin) {
  Histogram histogram;
  histogram.title = "Empty";
  histogram.series.push_back({"s", {kNan}});
  const HistogramBins bins = computeHistogramBins(histogram);
  EXPECT_EQ(bins.edges, (std::vector<double>{0.0, 1.0}));
  EXPECT_EQ(bins.counts[0], (std::vector<std::size_t>{0}));
  EXPECT_EQ(bins.missing[0], 1U);
}

}  // namespace
}  // namespace fullarm::reports
