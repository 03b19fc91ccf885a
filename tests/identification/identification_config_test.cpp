// The identification settings: the shipped file loads with the values it states, and each kind
// of mistake is a ConfigError naming the key path and the line.

#include "fullarm/identification/identification_config.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "fullarm/core/config_error.hpp"

namespace fullarm::identification {
namespace {

std::string shippedText() {
  const char* root = std::getenv("FULLARM_SOURCE_DIR");
  std::ifstream in(std::string(root != nullptr ? root : ".") + "/config/identification.yaml");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

core::ConfigError errorOf(const std::string& text) {
  try {
    (void)parseIdentificationConfig(text, "identification.yaml");
  } catch (const core::ConfigError& e) {
    return e;
  }
  ADD_FAILURE() << "accepted";
  return core::ConfigError("", "", "");
}

TEST(IdentificationConfigTest, ShippedFileLoads) {
  const IdentificationConfig c = parseIdentificationConfig(shippedText(), "identification.yaml");
  EXPECT_EQ(c.fit.max_delay_samples, 4);
  EXPECT_EQ(c.fit.global_samples, 100);
  EXPECT_TRUE(c.fit.params[kFlowGain].free);
  EXPECT_TRUE(c.fit.params[kFlowGain].log_scaled);
  EXPECT_DOUBLE_EQ(c.fit.params[kStiffness].max, 2.0e5);
  EXPECT_FALSE(c.fit.params[kAngleOffset].free);
  EXPECT_FALSE(c.fit.params[kLoadTorque].log_scaled);
  EXPECT_DOUBLE_EQ(c.validation.min_fit_angle_percent, 90.0);
  EXPECT_EQ(c.validation.max_lag, 25);
  EXPECT_DOUBLE_EQ(c.coulomb_smoothing_radps, 0.01);
  EXPECT_DOUBLE_EQ(c.stribeck_velocity_radps, 0.05);
  EXPECT_FALSE(c.fit.params[kStribeck].free);
  EXPECT_EQ(c.fit.jacobian, JacobianMethod::kSensitivities);
  EXPECT_TRUE(c.fit.initial_speed.free);
  EXPECT_FALSE(c.fit.initial_speed.log_scaled);
  EXPECT_DOUBLE_EQ(c.fit.initial_speed.max, 5.0);
  EXPECT_TRUE(c.fit.initial_torque_offset.free);
  EXPECT_DOUBLE_EQ(c.fit.initial_torque_offset.min, -60.0);
  const IdentificationConfig cd = parseIdentificationConfig(
      replaced(shippedText(), "jacobian: sensitivities", "jacobian: central_differences"), "identification.yaml");
  EXPECT_EQ(cd.fit.jacobian, JacobianMethod::kCentralDifferences);
  const IdentificationConfig rest = parseIdentificationConfig(
      replaced(shippedText(), "speed_radps:      {mode: free", "speed_radps:      {mode: fixed"),
      "identification.yaml");
  EXPECT_FALSE(rest.fit.initial_speed.free);
  EXPECT_TRUE(std::filesystem::exists(loadIdentificationConfig(defaultIdentificationConfigPath()).source));
}

TEST(IdentificationConfigTest, MistakesNameTheKeyAndTheLine) {
  const std::string text = shippedText();
  const auto log_zero = errorOf(replaced(text, "scaling: log, min: 0.05", "scaling: log, min: 0.0"));
  EXPECT_EQ(log_zero.keyPath(), "parameters.flow_gain_radps_per_v.min");
  EXPECT_GT(log_zero.line(), 0);
  const auto inverted = errorOf(replaced(text, "min: 500.0, max: 2.0e5", "min: 500.0, max: 100.0"));
  EXPECT_EQ(inverted.keyPath(), "parameters.hydraulic_stiffness_nm_per_rad.max");
  const auto scaling = errorOf(replaced(text, "scaling: linear, min: -60.0", "scaling: cubic, min: -60.0"));
  EXPECT_EQ(scaling.keyPath(), "parameters.load_torque_nm.scaling");
  const auto unknown = errorOf(replaced(text, "  seed: 1\n", "  seed: 1\n  sede: 2\n"));
  EXPECT_NE(std::string(unknown.what()).find("sede"), std::string::npos) << unknown.what();
  const auto missing = errorOf(replaced(text, "  max_lag: 25 ", "  #max_lag: 25 "));
  EXPECT_NE(std::string(missing.what()).find("max_lag"), std::string::npos) << missing.what();
  const auto fraction =
      errorOf(replaced(text, "whiteness_max_outside_fraction: 0.1", "whiteness_max_outside_fraction: 1.5"));
  EXPECT_EQ(fraction.keyPath(), "validation.whiteness_max_outside_fraction");
  const auto independence =
      errorOf(replaced(text, "independence_max_outside_fraction: 0.1", "independence_max_outside_fraction: -0.1"));
  EXPECT_EQ(independence.keyPath(), "validation.independence_max_outside_fraction");
  const auto cell = errorOf(replaced(text, "torque_cell_noise_nm: 0.05", "torque_cell_noise_nm: -0.05"));
  EXPECT_EQ(cell.keyPath(), "validation.prediction.torque_cell_noise_nm");
  const auto jacobian = errorOf(replaced(text, "jacobian: sensitivities", "jacobian: secant"));
  EXPECT_EQ(jacobian.keyPath(), "fit.jacobian");
  EXPECT_GT(jacobian.line(), 0);
  const auto off_rest =
      errorOf(replaced(text, "{mode: free, min: -5.0, max: 5.0}", "{mode: free, min: 0.5, max: 5.0}"));
  EXPECT_EQ(off_rest.keyPath(), "initial_states.speed_radps.min");
  EXPECT_GT(off_rest.line(), 0);
  const auto below =
      errorOf(replaced(text, "{mode: free, min: -60.0, max: 60.0}", "{mode: free, min: -60.0, max: -1.0}"));
  EXPECT_EQ(below.keyPath(), "initial_states.torque_offset_nm.max");
  const auto mode = errorOf(replaced(text, "torque_offset_nm: {mode: free", "torque_offset_nm: {mode: loose"));
  EXPECT_EQ(mode.keyPath(), "initial_states.torque_offset_nm.mode");
  const auto extra =
      errorOf(replaced(text, "{mode: free, min: -5.0, max: 5.0}", "{mode: free, min: -2.0, max: 2.0, scaling: log}"));
  EXPECT_NE(std::string(extra.what()).find("scaling"), std::string::npos) << extra.what();
  EXPECT_THROW((void)loadIdentificationConfig("/nonexistent/identification.yaml"), core::ConfigError);
}

}  // namespace
}  // namespace fullarm::identification
