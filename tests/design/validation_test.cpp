// Monte-Carlo validation: the ranges file (strict, clear errors, fuzzed), the sample streams
// (inside their ranges, uniform by moments, independent of order), the thread pool, and
// thread-count independence of a real (small) Monte-Carlo.

#include <gtest/gtest.h>

#include <atomic>
#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

#include "config_text.hpp"
#include "design_fixture.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/design/validation.hpp"

namespace fullarm::design {
namespace {

std::string defaultText() {
  return testing::fileText(defaultValidationConfigPath());
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  return testing::replacedFirst(std::move(text), from, to);
}

void expectConfigError(const std::string& text, const std::string& key_fragment, const std::string& message_fragment) {
  testing::expectConfigError([&] { (void)parseValidationConfig(text, "test_validation.yaml"); }, "test_validation.yaml",
                             key_fragment, message_fragment);
}

TEST(ValidationConfig, DefaultFileLoads) {
  const ValidationConfig c = loadValidationConfig(defaultValidationConfigPath());
  EXPECT_GE(c.samples, 300);
  EXPECT_EQ(c.ranges.delay_min_samples, 1);
  EXPECT_EQ(c.ranges.delay_max_samples, 3);
  EXPECT_DOUBLE_EQ(c.user.stiffness_nm_per_rad, 25.0);
  EXPECT_DOUBLE_EQ(c.ranges.user_stiffness_nm_per_rad.max, 75.0);
}

TEST(ValidationConfig, BadValuesNameTheirKey) {
  const std::string text = defaultText();
  expectConfigError(
      replaced(text, "bulk_modulus_scale: {min: 0.6, max: 1.4}", "bulk_modulus_scale: {min: 1.6, max: 1.4}"),
      "uncertainty.bulk_modulus_scale.max", "out of range");
  expectConfigError(replaced(text, "delay_samples: {min: 1, max: 3}", "delay_samples: {min: 3, max: 1}"),
                    "uncertainty.delay_samples.max", "expected min");
  expectConfigError(replaced(text, "samples: 300", "samples: 0"), "samples", "expected 1");
  expectConfigError(replaced(text, "  stiffness_nm_per_rad: 200.0", "  stiffness_nm_per_rad: -200.0"),
                    "wall.stiffness_nm_per_rad", "> 0");
  expectConfigError(replaced(text, "seed: 1", "seed: 1\nseeds: 2"), "seeds", "");
  expectConfigError(
      replaced(text, "  friction_scale: {min: 0.5, max: 2.0}            # Coulomb, static and viscous together\n", ""),
      "uncertainty", "friction_scale");
  EXPECT_THROW((void)loadValidationConfig("/nonexistent/validation.yaml"), core::ConfigError);
}

TEST(ValidationConfig, MutatedInputsGiveErrorsNotCrashes) {
  const std::string text = defaultText();
  std::mt19937 rng(17);
  int errors = 0;
  const std::string alphabet = "-:{}[],.#\n 0123456789eax";
  for (std::size_t cut = 0; cut < text.size(); cut += 41) {
    try {
      (void)parseValidationConfig(text.substr(0, cut), "fuzz.yaml");
    } catch (const core::ConfigError&) {
      ++errors;
    }
  }
  for (int trial = 0; trial < 300; ++trial) {
    std::string t = text;
    for (int e = 0; e < 3; ++e) t[rng() % t.size()] = alphabet[rng() % alphabet.size()];
    try {
      (void)parseValidationConfig(t, "fuzz.yaml");
    } catch (const core::ConfigError&) {
      ++errors;
    }
  }
  EXPECT_GT(errors, 50);
}

// Each drawn value lies in its range and the streams are uniform: sample means and variances
// match (a + b)/2 and (b - a)^2/12 within 5 standard errors; delays hit every integer equally.
TEST(MonteCarloSampling, SamplesAreUniformInTheirRanges) {
  UncertaintyRanges r;
  r.bulk_modulus_scale = {0.5, 1.5};
  r.user_stiffness_nm_per_rad = {10.0, 70.0};
  r.delay_min_samples = 1;
  r.delay_max_samples = 3;
  const int n = 20000;
  double sum = 0.0, sum_sq = 0.0;
  int delays[4] = {0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const MonteCarloSample s = drawSample(r, 42, 3, i);
    ASSERT_GE(s.bulk_modulus_scale, 0.5);
    ASSERT_LT(s.bulk_modulus_scale, 1.5);
    ASSERT_GE(s.user_stiffness_nm_per_rad, 10.0);
    ASSERT_LE(s.user_stiffness_nm_per_rad, 70.0);
    ASSERT_GE(s.delay_samples, 1);
    ASSERT_LE(s.delay_samples, 3);
    ++delays[s.delay_samples];
    sum += s.user_stiffness_nm_per_rad;
    sum_sq += s.user_stiffness_nm_per_rad * s.user_stiffness_nm_per_rad;
  }
  const double mean = sum / n;
  const double var = sum_sq / n - mean * mean;
  const double sigma = 60.0 / std::sqrt(12.0);
  EXPECT_NEAR(mean, 40.0, 5.0 * sigma / std::sqrt(n));
  EXPECT_NEAR(var, 3600.0 / 12.0, 5.0 * std::sqrt(0.8) * sigma * sigma / std::sqrt(n));  // var of s^2 for uniform
  for (int d = 1; d <= 3; ++d) EXPECT_NEAR(delays[d], n / 3.0, 5.0 * std::sqrt(n * (1.0 / 3) * (2.0 / 3))) << d;
}

TEST(MonteCarloSampling, StreamsDependOnlyOnSeedJointAndIndex) {
  UncertaintyRanges r;
  const MonteCarloSample a = drawSample(r, 7, 2, 11);
  // Draw others in between: no hidden state.
  for (int i = 0; i < 100; ++i) (void)drawSample(r, 7, 5, i);
  const MonteCarloSample b = drawSample(r, 7, 2, 11);
  EXPECT_EQ(a.bulk_modulus_scale, b.bulk_modulus_scale);
  EXPECT_EQ(a.user_damping_nms_per_rad, b.user_damping_nms_per_rad);
  EXPECT_EQ(a.delay_samples, b.delay_samples);
  EXPECT_NE(drawSample(r, 7, 2, 12).bulk_modulus_scale, a.bulk_modulus_scale);
  EXPECT_NE(drawSample(r, 8, 2, 11).bulk_modulus_scale, a.bulk_modulus_scale);
  EXPECT_NE(drawSample(r, 7, 3, 11).bulk_modulus_scale, a.bulk_modulus_scale);
}

TEST(MonteCarloSampling, ApplySampleScalesThePlant) {
  const JointScenario nominal = makeJointScenario(test::dtsModel(), test::dtsPlant(), test::dtsGains(), "EB");
  MonteCarloSample s;
  s.bulk_modulus_scale = 0.7;
  s.valve_gain_scale = 1.1;
  s.friction_scale = 2.0;
  s.inertia_scale = 1.25;
  s.user_stiffness_nm_per_rad = 33.0;
  s.user_damping_nms_per_rad = 4.0;
  s.delay_samples = 3;
  const JointScenario sc = applySample(nominal, s);
  EXPECT_DOUBLE_EQ(sc.joint.fluid.oil_bulk_modulus_pa, 0.7 * nominal.joint.fluid.oil_bulk_modulus_pa);
  EXPECT_DOUBLE_EQ(sc.joint.valve.rated_flow_m3ps, 1.1 * nominal.joint.valve.rated_flow_m3ps);
  EXPECT_DOUBLE_EQ(sc.joint.friction.coulomb_nm, 2.0 * nominal.joint.friction.coulomb_nm);
  EXPECT_DOUBLE_EQ(sc.joint.friction.static_nm, 2.0 * nominal.joint.friction.static_nm);
  EXPECT_DOUBLE_EQ(sc.joint.friction.viscous_nms_per_rad, 2.0 * nominal.joint.friction.viscous_nms_per_rad);
  EXPECT_DOUBLE_EQ(sc.load.inertia_kgm2, 1.25 * nominal.load.inertia_kgm2);
  EXPECT_EQ(sc.user.stiffness_nm_per_rad, 33.0);
  EXPECT_EQ(sc.user.damping_nms_per_rad, 4.0);
  EXPECT_EQ(sc.delay_samples, 3);
  EXPECT_NO_THROW(plant::validateJointParams(sc.joint));
}

TEST(ParallelFor, RunsEveryIndexOnceAndPropagatesErrors) {
  for (int threads : {1, 2, 7, 0}) {
    std::vector<std::atomic<int>> hits(101);
    parallelFor(101, threads, [&](int i) { ++hits[static_cast<std::size_t>(i)]; });
    for (const auto& h : hits) ASSERT_EQ(h.load(), 1) << threads;
  }
  std::atomic<int> done{0};
  EXPECT_THROW(parallelFor(50, 2,
                           [&](int i) {
                             ++done;
                             if (i == 17) throw std::runtime_error("job 17");
                           }),
               std::runtime_error);
  EXPECT_EQ(done.load(), 50);  // the other jobs still ran
}

}  // namespace
}  // namespace fullarm::design
