// Gains YAML: strict reading, validation with errors naming file/line/key path, round trip
// through formatGainsYaml, and fuzz-style mutations (errors, never crashes).

#include <gtest/gtest.h>

#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "config_text.hpp"
#include "controllers_fixture.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::controllers {
namespace {

std::string defaultText() {
  return testing::fileText(defaultGainsConfigPath());
}

// Replaces the first `from` at or after the joint called `joint` (or the file start); when the
// literal is not there, the first `key: value` of `from` = "key: value" by `to`, whatever the
// file's value is (the default file may be written by
// `fullarm tune`, so its values are not fixed). A `from` ending in a newline names a whole line
// "    key: value\n", replaced whole.
std::string replaced(std::string text, const std::string& from, const std::string& to, const std::string& joint = {}) {
  std::size_t start = joint.empty() ? 0 : text.find("name: " + joint);
  if (start == std::string::npos) start = 0;
  const std::size_t colon = from.find(':');
  // The literal, as a whole value (not the prefix of a longer number).
  for (std::size_t at = text.find(from, start); at != std::string::npos; at = text.find(from, at + 1)) {
    const std::size_t after = at + from.size();
    if (colon == std::string::npos || from.back() == '\n' || after >= text.size() ||
        std::string(",} \n").find(text[after]) != std::string::npos) {
      return text.replace(at, from.size(), to);
    }
  }
  if (colon == std::string::npos) return text;
  const std::string key = from.substr(0, colon + 1);
  if (!from.empty() && from.back() == '\n') {
    const std::size_t line = text.find("\n" + key, start);
    if (line == std::string::npos) return text;
    const std::size_t end = text.find('\n', line + 1);
    return text.replace(line + 1, end - line, to);
  }
  const std::size_t at = text.find(key, start);
  if (at == std::string::npos) return text;
  const std::size_t end = text.find_first_of(",}\n", at);
  return text.replace(at, end - at, to);
}

void expectConfigError(const std::string& text, const std::string& key_fragment, const std::string& message_fragment) {
  testing::expectConfigError([&] { (void)parseGainsConfig(text, "test_gains.yaml", test::dtsModel()); },
                             "test_gains.yaml", key_fragment, message_fragment);
}

TEST(GainsConfig, DefaultFileLoads) {
  const GainsConfig& g = test::dtsGains();
  ASSERT_EQ(g.joints.size(), 7u);
  EXPECT_EQ(g.controller, ControllerKind::kAdmittance);
  EXPECT_DOUBLE_EQ(g.control_period_s, 1e-3);
  EXPECT_EQ(g.joints[static_cast<std::size_t>(findGainsJoint(g, "EB"))].name, "R_EB");
  EXPECT_EQ(findGainsJoint(g, "R_EB"), findGainsJoint(g, "EB"));
  EXPECT_THROW((void)findGainsJoint(g, "ELBOW"), core::ConfigError);
}

TEST(GainsConfig, NegativeInertiaIsAClearError) {
  expectConfigError(replaced(defaultText(), "inertia_kgm2: 0.2", "inertia_kgm2: -0.2", "R_EB"),
                    "joints[3].impedance.inertia_kgm2", "J_m > 0");
}

TEST(GainsConfig, NonPositiveEpsilonIsAClearError) {
  for (const char* eps : {"0.0", "-0.5"}) {
    expectConfigError(
        replaced(defaultText(), "boundary_layer_radps: 48.0", std::string("boundary_layer_radps: ") + eps, "R_WR"),
        "joints[4].sliding_mode.boundary_layer_radps", "eps > 0");
  }
}

TEST(GainsConfig, UnknownJointIsAClearError) {
  expectConfigError(replaced(defaultText(), "name: R_EB", "name: R_ELBOW"), "joints[3].name",
                    "unknown joint 'R_ELBOW'");
  // A hand joint has no valve.
  expectConfigError(replaced(defaultText(), "name: R_EB", "name: R_TL"), "joints[3].name", "hand joint");
  expectConfigError(replaced(defaultText(), "name: R_EB", "name: R_SFE"), "joints[3].name", "listed twice");
}

TEST(GainsConfig, OtherBadValuesNameTheirKey) {
  const std::string text = defaultText();
  expectConfigError(replaced(text, "controller: admittance", "controller: lqr"), "controller",
                    "admittance or torque_pid");
  expectConfigError(replaced(text, "control_period_s: 0.001", "control_period_s: 0"), "control_period_s", "range");
  expectConfigError(replaced(text, "valve_bound_v: 5.0", "valve_bound_v: 12.0"), "joints[0].sliding_mode.valve_bound_v",
                    "valve_limit_v");
  expectConfigError(replaced(text, "torque_filter_hz: 0.0", "torque_filter_hz: 600.0", "R_HR"),
                    "joints[2].torque_filter_hz", "Nyquist");
  expectConfigError(replaced(text, "kp_v_per_nm: 0.1", "kp_v_per_nm: -0.1"), "joints[0].torque_pid.kp_v_per_nm",
                    ">= 0");
  expectConfigError(replaced(text, "enabled: false", "enabled: maybe"), "joints[0].passivity.enabled", "true or false");
  expectConfigError(replaced(text, "    valve_limit_v: 10.0\n", "    valve_limit_v: 10.0\n    valve_limt_v: 1\n"),
                    "joints[0].valve_limt_v", "");
  expectConfigError(replaced(text, "    error_rate_filter_hz: 0.0\n", ""), "joints[0]", "error_rate_filter_hz");
  expectConfigError(replaced(text, "lambda_per_s: 300.0", "lambda_per_s: .nan"), "joints[0].sliding_mode.lambda_per_s",
                    "");
}

TEST(GainsConfig, SyntaxAndFileErrors) {
  EXPECT_THROW((void)parseGainsConfig("joints: [", "broken.yaml", test::dtsModel()), core::ConfigError);
  EXPECT_THROW((void)loadGainsConfig("/nonexistent/gains.yaml", test::dtsModel()), core::ConfigError);
  EXPECT_THROW(
      (void)parseGainsConfig("schema_version: 1\ncontroller: admittance\ncontrol_period_s: 0.001\njoints: []\n",
                             "empty.yaml", test::dtsModel()),
      core::ConfigError);
}

TEST(GainsConfig, FormatRoundTripsExactly) {
  GainsConfig g = test::dtsGains();
  g.controller = ControllerKind::kTorquePid;
  g.joints[1].impedance.inertia_kgm2 = 0.1 / 3.0;  // not representable in few digits
  g.joints[1].passivity.enabled = true;
  g.joints[2].torque_filter_hz = 123.456789012345;
  const GainsConfig back = parseGainsConfig(formatGainsYaml(g), "round_trip.yaml", test::dtsModel());
  ASSERT_EQ(back.joints.size(), g.joints.size());
  EXPECT_EQ(back.controller, ControllerKind::kTorquePid);
  EXPECT_EQ(back.joints[1].impedance.inertia_kgm2, g.joints[1].impedance.inertia_kgm2);
  EXPECT_TRUE(back.joints[1].passivity.enabled);
  EXPECT_EQ(back.joints[2].torque_filter_hz, g.joints[2].torque_filter_hz);
  EXPECT_EQ(back.joints[6].sliding_mode.boundary_layer_radps, g.joints[6].sliding_mode.boundary_layer_radps);
}

// Fuzz-style: truncations and random byte mutations of the default file either parse to a
// valid configuration or throw core::ConfigError; nothing else escapes.
TEST(GainsConfig, MutatedInputsGiveErrorsNotCrashes) {
  const std::string text = defaultText();
  std::mt19937 rng(11);
  int errors = 0;
  auto attempt = [&](const std::string& t) {
    try {
      const GainsConfig g = parseGainsConfig(t, "fuzz.yaml", test::dtsModel());
      for (const JointGains& j : g.joints) validateJointGains(j, g.control_period_s);
    } catch (const core::ConfigError&) {
      ++errors;
    }
  };
  for (std::size_t cut = 0; cut < text.size(); cut += 37) attempt(text.substr(0, cut));
  const std::string alphabet = "-:{}[],.#\n 0123456789eanx\"'";
  for (int trial = 0; trial < 300; ++trial) {
    std::string t = text;
    const int edits = 1 + static_cast<int>(rng() % 4);
    for (int e = 0; e < edits; ++e) {
      const std::size_t at = rng() % t.size();
      t[at] = alphabet[rng() % alphabet.size()];
    }
    attempt(t);
  }
  EXPECT_GT(errors, 100);  // most mutations are errors; the point is that none crashed
}

}  // namespace
}  // namespace fullarm::controllers
