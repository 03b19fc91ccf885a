#include "fullarm/accessibility/population_shares.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "arm_test_util.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::accessibility {
namespace {

constexpr double kZ975 = 1.959963984540054;  // standard normal 97.5th percentile

// Binomial probabilities summed term by term with the coefficient built by multiplication: a
// second implementation beside the library's log-gamma sums.
double binomialPmf(int k, int n, double p) {
  double c = 1.0;
  for (int i = 1; i <= k; ++i) c = c * (n - k + i) / i;
  return c * std::pow(p, k) * std::pow(1.0 - p, n - k);
}
double atLeast(int k, int n, double p) {
  double s = 0.0;
  for (int i = k; i <= n; ++i) s += binomialPmf(i, n, p);
  return s;
}
double atMost(int k, int n, double p) {
  double s = 0.0;
  for (int i = 0; i <= k; ++i) s += binomialPmf(i, n, p);
  return s;
}

TEST(PopulationShares, ClopperPearsonBoundsHaveTheExactBinomialTailProbabilities) {
  for (const int n : {1, 7, 20, 29, 60}) {
    for (int x = 0; x <= n; ++x) {
      const ShareInterval s = clopperPearsonInterval(x, n);
      EXPECT_DOUBLE_EQ(s.share, static_cast<double>(x) / n);
      if (x > 0) {
        EXPECT_NEAR(atLeast(x, n, s.lower), 0.025, 1e-9) << x << "/" << n;
      } else {
        EXPECT_EQ(s.lower, 0.0);
      }
      if (x < n) {
        EXPECT_NEAR(atMost(x, n, s.upper), 0.025, 1e-9) << x << "/" << n;
      } else {
        EXPECT_EQ(s.upper, 1.0);
      }
    }
  }
}

TEST(PopulationShares, ClopperPearsonAtTheEndsHasItsClosedForm) {
  // x = 0: upper = 1 - (alpha/2)^(1/n); x = n: lower = (alpha/2)^(1/n).
  for (const int n : {5, 20, 1000}) {
    EXPECT_NEAR(clopperPearsonInterval(0, n).upper, 1.0 - std::pow(0.025, 1.0 / n), 1e-12);
    EXPECT_NEAR(clopperPearsonInterval(n, n).lower, std::pow(0.025, 1.0 / n), 1e-12);
  }
  // 90 % confidence changes alpha.
  EXPECT_NEAR(clopperPearsonInterval(0, 20, 0.90).upper, 1.0 - std::pow(0.05, 1.0 / 20), 1e-12);
}

TEST(PopulationShares, WilsonBoundsSolveTheScoreEquation) {
  for (const int n : {1, 10, 263, 1000}) {
    for (const int x : {0, 1, n / 3, n / 2, n - 1, n}) {
      if (x < 0 || x > n) continue;
      const ShareInterval s = wilsonInterval(x, n);
      const double ph = static_cast<double>(x) / n;
      for (const double p : {s.lower, s.upper}) {
        // |ph - p| = z sqrt(p (1 - p) / n)
        EXPECT_NEAR(std::abs(ph - p), kZ975 * std::sqrt(p * (1.0 - p) / n), 1e-12) << x << "/" << n;
      }
      EXPECT_LE(s.lower, ph);
      EXPECT_GE(s.upper, ph);
    }
  }
}

TEST(PopulationShares, WilsonIsInsideClopperPearsonForLargeSamples) {
  // The exact interval is conservative: wider than Wilson's for these counts.
  for (const int x : {81, 500, 950}) {
    const ShareInterval w = wilsonInterval(x, 1000);
    const ShareInterval c = clopperPearsonInterval(x, 1000);
    EXPECT_LT(c.lower, w.lower);
    EXPECT_GT(c.upper, w.upper);
    EXPECT_NEAR(c.lower, w.lower, 0.01);
    EXPECT_NEAR(c.upper, w.upper, 0.01);
  }
}

TEST(PopulationShares, BadCountsAreRefused) {
  EXPECT_THROW((void)wilsonInterval(0, 0), std::invalid_argument);
  EXPECT_THROW((void)wilsonInterval(-1, 5), std::invalid_argument);
  EXPECT_THROW((void)clopperPearsonInterval(6, 5), std::invalid_argument);
  EXPECT_THROW((void)clopperPearsonInterval(2, 5, 1.0), std::invalid_argument);
  EXPECT_THROW((void)wilsonInterval(2, 5, std::nan("")), std::invalid_argument);
  EXPECT_THROW((void)summariseCriterion({}, {}), std::invalid_argument);
  EXPECT_THROW((void)summariseCriterion({Technician{}}, {true, false}), std::invalid_argument);
}

std::vector<Technician> population(std::int64_t n) {
  PopulationOptions options;
  options.female_share = 0.5;
  options.seed = 99;
  std::vector<Technician> t;
  for (std::int64_t i = 0; i < n; ++i) t.push_back(drawTechnician(options, i, arm::test::defaultModel()));
  return t;
}

TEST(PopulationShares, TheLogisticFitRecoversKnownCoefficients) {
  // Outcomes drawn from a known logistic model on the standardised log factors.
  const std::vector<Technician> t = population(20000);
  std::array<std::vector<double>, 3> logs;
  for (const Technician& x : t) {
    logs[0].push_back(std::log(x.upper_arm_m));
    logs[1].push_back(std::log(x.forearm_m));
    logs[2].push_back(std::log(x.strength_scale));
  }
  std::array<double, 3> mean{};
  std::array<double, 3> sd{};
  for (int k = 0; k < 3; ++k) {
    for (const double v : logs[k]) mean[k] += v;
    mean[k] /= static_cast<double>(t.size());
    for (const double v : logs[k]) sd[k] += (v - mean[k]) * (v - mean[k]);
    sd[k] = std::sqrt(sd[k] / static_cast<double>(t.size() - 1));
  }
  const std::array<double, 4> b{0.4, 1.0, 0.0, 0.6};
  std::vector<bool> ok;
  for (std::size_t i = 0; i < t.size(); ++i) {
    double eta = b[0];
    for (int k = 0; k < 3; ++k) eta += b[k + 1] * (logs[k][i] - mean[k]) / sd[k];
    core::RandomStream rng(5, 6, i);
    ok.push_back(rng.uniform01() < 1.0 / (1.0 + std::exp(-eta)));
  }
  const CriterionSummary s = summariseCriterion(t, ok);
  // Standard errors at n = 20000 are about 0.02-0.03 (the factors correlate); 0.1 is 3-5 of them.
  EXPECT_NEAR(s.intercept, b[0], 0.1);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(s.log_odds_per_sd[static_cast<std::size_t>(k)], b[k + 1], 0.1) << k;
  EXPECT_FALSE(s.fit_separated);
  std::int64_t failures = 0;
  for (const auto f : s.failures_by_factor) failures += f;
  EXPECT_EQ(failures + s.failures_unexplained, s.wilson.trials - s.wilson.successes);
  // The forearm has no effect: it rarely is what limits a failure.
  EXPECT_LT(s.failures_by_factor[1] * 5, s.failures_by_factor[0]);
  EXPECT_LT(s.failures_by_factor[1] * 5, s.failures_by_factor[2]);
}

TEST(PopulationShares, AStrengthThresholdPutsTheFailuresOnStrength) {
  const std::vector<Technician> t = population(2000);
  std::vector<bool> ok;
  for (const Technician& x : t) ok.push_back(x.strength_scale > 0.6);
  const CriterionSummary s = summariseCriterion(t, ok);
  std::int64_t failures = s.wilson.trials - s.wilson.successes;
  ASSERT_GT(failures, 100);
  EXPECT_TRUE(s.fit_separated);
  EXPECT_EQ(s.failures_by_factor[2], failures);
  EXPECT_GT(s.log_odds_per_sd[2], 5.0);
  EXPECT_STREQ(factorName(PopulationFactor::kStrength), "strength");
}

TEST(PopulationShares, AFactorLeftOutIsNeverTheLimitingOne) {
  // Success set by arm length alone; strength correlates with size (0.3 on the log scale) and
  // by chance in a finite sample, so with all three factors its coefficient is not zero.
  const std::vector<Technician> t = population(400);
  std::vector<double> reach;
  for (const Technician& x : t) reach.push_back(x.upper_arm_m + x.forearm_m);
  std::vector<double> sorted = reach;
  std::sort(sorted.begin(), sorted.end());
  const double cut = sorted[sorted.size() / 3];
  std::vector<bool> ok;
  for (const double r : reach) ok.push_back(r > cut);
  const CriterionSummary all = summariseCriterion(t, ok);
  const CriterionSummary size = summariseCriterion(t, ok, 0.95, kSizeFactors);
  EXPECT_EQ(size.log_odds_per_sd[2], 0.0);
  EXPECT_EQ(size.failures_by_factor[2], 0);
  const std::int64_t failures = size.wilson.trials - size.wilson.successes;
  EXPECT_EQ(size.failures_by_factor[0] + size.failures_by_factor[1] + size.failures_unexplained, failures);
  EXPECT_NE(all.log_odds_per_sd[2], 0.0);
  // The shares and intervals do not depend on the factors.
  EXPECT_EQ(size.wilson.share, all.wilson.share);
  EXPECT_EQ(size.clopper_pearson.lower, all.clopper_pearson.lower);
}

TEST(PopulationShares, EveryoneSucceedingGivesAShareOfOneAndNoFit) {
  const std::vector<Technician> t = population(50);
  const CriterionSummary s = summariseCriterion(t, std::vector<bool>(50, true));
  EXPECT_EQ(s.wilson.share, 1.0);
  EXPECT_EQ(s.clopper_pearson.upper, 1.0);
  EXPECT_NEAR(s.clopper_pearson.lower, std::pow(0.025, 1.0 / 50), 1e-12);
  EXPECT_EQ(s.log_odds_per_sd[0], 0.0);
  EXPECT_EQ(s.failures_unexplained, 0);
  const CriterionSummary none = summariseCriterion(t, std::vector<bool>(50, false));
  EXPECT_EQ(none.failures_unexplained, 50);
  EXPECT_EQ(none.clopper_pearson.lower, 0.0);
}

}  // namespace
}  // namespace fullarm::accessibility
