// Monte-Carlo validation: the ranges file (strict, clear errors, fuzzed), the thread pool, and
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
