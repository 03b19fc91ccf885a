// identified.yaml: written and read back to the same doubles, read strictly.

#include "fullarm/identification/identified_model.hpp"

#include <gtest/gtest.h>

#include <string>

#include "fullarm/core/config_error.hpp"

namespace fullarm::identification {
namespace {

IdentifiedModel sample() {
  IdentifiedModel id;
  id.joint = "R_EB";
  id.model.value = {0.41234567890123456, 6.6e3 / 3.0, 1.0e-5 / 7.0, 0.3125, 0.5, 1.1, 0.25 / 3.0, -3.3, 0.01, 0.0, 0.0};
  id.model.delay_samples = 2;
  id.model.coulomb_smoothing_radps = 0.05;
  id.model.spool_hz = 150.0;
  id.model.spool_damping = 0.7;
  id.model.torque_filter_hz = 200.0 / 3.0;
  id.model.stribeck_velocity_radps = 0.05 / 3.0;
  id.model.stall_torque_nm = 60.147262717770488;
  id.model.underlap_v = 0.04 / 3.0;
  id.model.edge_rounding_v = 0.02 / 7.0;
  id.model.load_gradient_nm_per_rad = -1.0 / 3.0;
  for (int i = 0; i < kGreyParams; ++i) id.standard_error[static_cast<std::size_t>(i)] = 1.0 / (i + 3.0);
  id.standard_error[kAngleOffset] = 0.0;
  return id;
}

TEST(IdentifiedModelTest, ReadsBackTheSameDoubles) {
  const IdentifiedModel want = sample();
  const IdentifiedModel got = parseIdentifiedModelYaml(formatIdentifiedModelYaml(want), "identified.yaml");
  EXPECT_EQ(got.joint, want.joint);
  EXPECT_EQ(got.model.delay_samples, want.model.delay_samples);
  EXPECT_EQ(got.model.spool_hz, want.model.spool_hz);
  EXPECT_EQ(got.model.spool_damping, want.model.spool_damping);
  EXPECT_EQ(got.model.torque_filter_hz, want.model.torque_filter_hz);
  EXPECT_EQ(got.model.coulomb_smoothing_radps, want.model.coulomb_smoothing_radps);
  EXPECT_EQ(got.model.stribeck_velocity_radps, want.model.stribeck_velocity_radps);
  EXPECT_EQ(got.model.stall_torque_nm, want.model.stall_torque_nm);
  EXPECT_EQ(got.model.underlap_v, want.model.underlap_v);
  EXPECT_EQ(got.model.edge_rounding_v, want.model.edge_rounding_v);
  EXPECT_EQ(got.model.load_gradient_nm_per_rad, want.model.load_gradient_nm_per_rad);
  for (int i = 0; i < kGreyParams; ++i) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_EQ(got.model.value[k], want.model.value[k]) << greyParamName(i);
    EXPECT_EQ(got.standard_error[k], want.standard_error[k]) << greyParamName(i);
  }
}

// The error for `text`, or "" when it parses.
std::string errorOf(const std::string& text) {
  try {
    static_cast<void>(parseIdentifiedModelYaml(text, "bad.yaml"));
  } catch (const core::ConfigError& e) {
    return e.what();
  }
  return "";
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

TEST(IdentifiedModelTest, RefusesMalformedFilesNamingTheKey) {
  const std::string good = formatIdentifiedModelYaml(sample());
  ASSERT_EQ(errorOf(good), "");
  const std::string unknown = errorOf(good + "extra: 1\n");
  EXPECT_NE(unknown.find("extra"), std::string::npos) << unknown;
  const std::string missing = errorOf(replaced(good, "delay_samples: 2\n", ""));
  EXPECT_NE(missing.find("delay_samples"), std::string::npos) << missing;
  const std::string negative_se = errorOf(replaced(good, "standard_error: 0}", "standard_error: -1}"));
  EXPECT_NE(negative_se.find("standard_error"), std::string::npos) << negative_se;
  const std::string nonpositive = errorOf(replaced(good, "inertia_kgm2: {value: 0.3125", "inertia_kgm2: {value: 0"));
  EXPECT_NE(nonpositive.find("parameters.inertia_kgm2.value"), std::string::npos) << nonpositive;
  const std::string not_number = errorOf(replaced(good, "spool_hz: 150", "spool_hz: fast"));
  EXPECT_NE(not_number.find("spool_hz"), std::string::npos) << not_number;
  EXPECT_NE(not_number.find("bad.yaml"), std::string::npos) << not_number;
}

}  // namespace
}  // namespace fullarm::identification
