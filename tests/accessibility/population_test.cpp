#include "fullarm/accessibility/population.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "alloc_guard.hpp"
#include "arm_test_util.hpp"
#include "fullarm/arm/arm_scaling.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/sweep.hpp"

namespace fullarm::accessibility {
namespace {

// Sample size: the standard error of a sample p-quantile is sqrt(p (1 - p) / n) / f(x_p). For the
// narrowest measure (upper arm, sd about 17.6 mm, f(x_5) = 0.103 / 17.6 mm) at n = 20000 it is
// 0.26 mm, so the 5 mm tolerance leaves more than 10 standard errors beside the at most 1.5 mm by
// which the log-normal misses the published 5th and 95th percentiles. The standard error of a
// correlation is (1 - r^2) / sqrt(n) = 0.0034: 0.03 is nearly 9 of them. Any seed passes; the
// seed is fixed so the run is reproducible.
constexpr std::int64_t kSample = 20000;
constexpr double kMm = 1e-3;

struct Drawn {
  std::vector<double> upper;
  std::vector<double> fore;
  std::vector<double> strength;
  std::vector<double> size_score;
  int women = 0;
};

Drawn draw(double female_share, std::int64_t n = kSample) {
  PopulationOptions options;
  options.female_share = female_share;
  options.seed = 2026;
  options.technicians = n;
  validatePopulationOptions(options);
  Drawn d;
  for (std::int64_t i = 0; i < n; ++i) {
    const Technician t = drawTechnician(options, i, arm::test::defaultModel());
    d.upper.push_back(t.upper_arm_m);
    d.fore.push_back(t.forearm_m);
    d.strength.push_back(t.strength_scale);
    d.women += t.female ? 1 : 0;
  }
  return d;
}

// Sample quantile, linear between order statistics (Hyndman and Fan type 7).
double quantile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const double h = (static_cast<double>(v.size()) - 1.0) * p;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, v.size() - 1);
  return v[lo] + (h - static_cast<double>(lo)) * (v[hi] - v[lo]);
}

double correlation(const std::vector<double>& a, const std::vector<double>& b) {
  const auto n = static_cast<double>(a.size());
  double ma = 0.0;
  double mb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ma += a[i];
    mb += b[i];
  }
  ma /= n;
  mb /= n;
  double sab = 0.0;
  double saa = 0.0;
  double sbb = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return sab / std::sqrt(saa * sbb);
}

void expectPercentiles(const std::vector<double>& v, double p5_mm, double p50_mm, double p95_mm, const char* what) {
  EXPECT_NEAR(quantile(v, 0.05) / kMm, p5_mm, 5.0) << what << " p5";
  EXPECT_NEAR(quantile(v, 0.50) / kMm, p50_mm, 5.0) << what << " p50";
  EXPECT_NEAR(quantile(v, 0.95) / kMm, p95_mm, 5.0) << what << " p95";
}

// The ANSUR II figures (men n = 4,082, women n = 1,986; docs/sources.md).
TEST(Population, MenMatchAnsurPercentilesAndCorrelation) {
  const Drawn d = draw(0.0);
  EXPECT_EQ(d.women, 0);
  expectPercentiles(d.upper, 307, 335, 365, "men's upper arm");
  expectPercentiles(d.fore, 244, 267, 295, "men's forearm");
  EXPECT_NEAR(correlation(d.upper, d.fore), 0.72, 0.03);
}

TEST(Population, WomenMatchAnsurPercentilesAndCorrelation) {
  const Drawn d = draw(1.0);
  EXPECT_EQ(d.women, kSample);
  expectPercentiles(d.upper, 283, 311, 340, "women's upper arm");
  expectPercentiles(d.fore, 218, 241, 268, "women's forearm");
  EXPECT_NEAR(correlation(d.upper, d.fore), 0.69, 0.03);
}

TEST(Population, AnEvenMixMatchesThePooledPercentiles) {
  const Drawn d = draw(0.5);
  // Binomial(20000, 0.5): sd 71; 5 sd.
  EXPECT_NEAR(d.women, kSample / 2, 355);
  expectPercentiles(d.upper, 289, 323, 358, "mixed upper arm");
  expectPercentiles(d.fore, 223, 254, 288, "mixed forearm");
}

TEST(Population, StrengthHasTheSexMedianTheSpreadAndAWeakLinkToSize) {
  for (const double share : {0.0, 1.0}) {
    const Drawn d = draw(share);
    const double median = share == 0.0 ? 1.0 : 0.45;
    // Median: SE about 1.25 sigma / sqrt(n) = 0.0022 relative.
    EXPECT_NEAR(quantile(d.strength, 0.5) / median, 1.0, 0.012);
    double mean = 0.0;
    for (const double s : d.strength) mean += s;
    mean /= static_cast<double>(d.strength.size());
    double var = 0.0;
    for (const double s : d.strength) var += (s - mean) * (s - mean);
    const double cv = std::sqrt(var / static_cast<double>(d.strength.size() - 1)) / mean;
    EXPECT_NEAR(cv, 0.25, 0.01);
    std::vector<double> log_strength;
    std::vector<double> log_size;
    for (std::size_t i = 0; i < d.strength.size(); ++i) {
      log_strength.push_back(std::log(d.strength[i]));
      log_size.push_back(std::log(d.upper[i]) + std::log(d.fore[i]));
    }
    // The size score weighs the two log-length scores equally; their log spreads differ by a few
    // per cent, so log(upper) + log(forearm) correlates with it at better than 0.999.
    EXPECT_NEAR(correlation(log_strength, log_size), 0.3, 0.03);
  }
}

TEST(Population, DrawsDependOnlyOnSeedAndIndex) {
  PopulationOptions options;
  const arm::ArmModel& model = arm::test::defaultModel();
  const Technician a = drawTechnician(options, 17, model);
  (void)drawTechnician(options, 3, model);
  const Technician b = drawTechnician(options, 17, model);
  EXPECT_EQ(a.upper_arm_m, b.upper_arm_m);
  EXPECT_EQ(a.forearm_m, b.forearm_m);
  EXPECT_EQ(a.strength_scale, b.strength_scale);
  options.seed += 1;
  EXPECT_NE(drawTechnician(options, 17, model).upper_arm_m, a.upper_arm_m);
}

TEST(Population, ThePopulationSweepIsTheSameOnOneAndTwoThreadsAndInTwoShards) {
  PopulationOptions options;
  options.technicians = 301;
  const arm::ArmModel& model = arm::test::defaultModel();
  const arm::ArmSize nominal = arm::armSizeOf(model);
  core::SweepSpec spec;
  spec.name = "technicians";
  spec.samples = options.technicians;
  spec.seed = options.seed;
  spec.values_per_sample = 4;
  const core::SweepFunction f = [&](std::int64_t i, core::RandomStream& rng, std::span<double> out) {
    const Technician t = drawTechnician(options, i, rng, *nominal.upper_arm_length_m, *nominal.forearm_length_m);
    out[0] = t.female ? 1.0 : 0.0;
    out[1] = t.upper_arm_m;
    out[2] = t.forearm_m;
    out[3] = t.strength_scale;
  };
  const core::SweepResults one = core::runSweep(spec, {1, 1}, f, 1);
  const core::SweepResults two = core::runSweep(spec, {1, 1}, f, 2);
  const core::SweepResults merged =
      core::mergeSweepResults({core::runSweep(spec, {2, 2}, f, 2), core::runSweep(spec, {1, 2}, f, 1)});
  EXPECT_EQ(one.values, two.values);
  EXPECT_EQ(one.values, merged.values);
  // The sweep's stream is the one drawTechnician(options, index, model) uses.
  const Technician t = drawTechnician(options, 123, model);
  EXPECT_EQ(one.row(123)[1], t.upper_arm_m);
  EXPECT_EQ(one.row(123)[3], t.strength_scale);
}

TEST(Population, TheTechniciansArmHasTheirLengthsAndScaledRadii) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Technician t = drawTechnician(PopulationOptions{}, 5, model);
  const arm::ArmModel scaled = technicianArm(model, t);
  const arm::ArmSize size = arm::armSizeOf(scaled);
  EXPECT_NEAR(*size.upper_arm_length_m, t.upper_arm_m, 1e-12);
  EXPECT_NEAR(*size.forearm_length_m, t.forearm_m, 1e-12);
  EXPECT_NEAR(*size.hand_length_m, *arm::armSizeOf(model).hand_length_m, 1e-12);
  const arm::ArmSize nominal = arm::armSizeOf(model);
  const double expected_scale =
      std::sqrt(t.upper_arm_m / *nominal.upper_arm_length_m * t.forearm_m / *nominal.forearm_length_m);
  EXPECT_NEAR(t.link_radius_scale, expected_scale, 1e-12);
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    EXPECT_NEAR(scaled.joints[j].geometry.radius_m, model.joints[j].geometry.radius_m * expected_scale, 1e-12);
  }
}

TEST(Population, TheTechniciansStrengthScalesEveryTorqueLimit) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const HumanArm nominal = loadHumanArm(defaultHumanArmPath(), model);
  const Technician t = drawTechnician(PopulationOptions{}, 9, model);
  const HumanArm human = technicianStrength(nominal, t);
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model.numJoints());
  Eigen::VectorXd lo0, hi0, lo, hi;
  computeTorqueLimits(nominal, q, lo0, hi0);
  computeTorqueLimits(human, q, lo, hi);
  for (Eigen::Index i = 0; i < lo.size(); ++i) {
    EXPECT_NEAR(hi[i], hi0[i] * t.strength_scale, 1e-9);
    EXPECT_NEAR(lo[i], lo0[i] * t.strength_scale, 1e-9);
  }
}

TEST(Population, DrawingATechnicianDoesNotAllocate) {
  const PopulationOptions options;
  core::RandomStream rng(1, 2, 3);
  Technician t;
  EXPECT_NO_HEAP_ALLOCATION(t = drawTechnician(options, 3, rng, 0.3, 0.28));
  EXPECT_GT(t.upper_arm_m, 0.0);
}

void expectOptionError(const PopulationOptions& options, const std::string& key, const std::string& fragment) {
  try {
    validatePopulationOptions(options);
    ADD_FAILURE() << "accepted";
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), key);
    EXPECT_NE(e.message().find(fragment), std::string::npos) << e.what();
  }
}

TEST(Population, BadOptionsAreRefusedWithClearErrors) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PopulationOptions o;
  o.technicians = 0;
  expectOptionError(o, "--population", "at least 1 technician");
  o.technicians = -5;
  expectOptionError(o, "--population", "-5");
  o = {};
  o.female_share = -0.1;
  expectOptionError(o, "--mix", "in [0, 1]");
  o.female_share = 1.5;
  expectOptionError(o, "--mix", "in [0, 1]");
  o.female_share = nan;
  expectOptionError(o, "--mix", "nan");
  o = {};
  o.figures.strength_cv = nan;
  expectOptionError(o, "population.figures.strength_cv", "0 < cv");
  o = {};
  o.figures.men.upper_arm_forearm_correlation = 1.0;
  expectOptionError(o, "population.figures.men.upper_arm_forearm_correlation", "-1 < r < 1");
  o = {};
  o.figures.women.forearm.p95_m = 0.2;
  expectOptionError(o, "population.figures.women.forearm", "p5 < p50 < p95");
  o = {};
  o.figures.women.strength_median = nan;
  expectOptionError(o, "population.figures.women.strength_median", "positive finite");
  o = {};
  EXPECT_NO_THROW(validatePopulationOptions(o));
  o.female_share = 0.0;
  EXPECT_NO_THROW(validatePopulationOptions(o));
  o.female_share = 1.0;
  EXPECT_NO_THROW(validatePopulationOptions(o));
}

}  // namespace
}  // namespace fullarm::accessibility
