// `fullarm tune` end to end: the tuned gains file loads with the gains loader `validate` uses,
// summary.json carries the per-joint results, bad input exits 2 with a message.

#include "cli_runner.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"

namespace {

using Result = fullarm::test::CliResult;
using fullarm::test::runFullarm;

std::filesystem::path tempDir(const std::string& name) {
  return fullarm::test::cliTempDir("fullarm_tune_cli_test", name);
}

TEST(TuneCli, WritesLoadableGainsAndSummary) {
  const auto dir = tempDir("eb");
  const Result r = runFullarm("tune --joints EB --global-evals 40 --local-evals 30 --rounds 1 --out " + dir.string());
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  const fullarm::controllers::GainsConfig gains = fullarm::controllers::loadGainsConfig(dir / "gains.yaml", model);
  EXPECT_EQ(gains.joints.size(), 7u);
  std::ifstream in(dir / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  const nlohmann::json& joints = summary["results"]["tune"]["joints"];
  ASSERT_EQ(joints.size(), 1u);
  EXPECT_EQ(joints[0]["joint"], "R_EB");
  EXPECT_EQ(summary["verdict"]["pass"].get<bool>(), r.exit_code == 0);
  // The tuned joint in the file is the one the summary reports: the nonlinear stage's result (it
  // may keep the starting gains instead of the linear stage's `tuned_gains`).
  const auto& eb = gains.joints[static_cast<std::size_t>(fullarm::controllers::findGainsJoint(gains, "EB"))];
  const nlohmann::json& written = summary["results"]["tune"]["nonlinear_stage"][0]["gains"];
  EXPECT_DOUBLE_EQ(eb.impedance.inertia_kgm2, written["inertia_kgm2"].get<double>());
  EXPECT_DOUBLE_EQ(eb.impedance.damping_nms_per_rad, written["damping_nms_per_rad"].get<double>());
  EXPECT_DOUBLE_EQ(eb.sliding_mode.boundary_layer_radps, written["boundary_layer_radps"].get<double>());
  EXPECT_TRUE(std::filesystem::exists(dir / "report.html"));
  // The written gains' linear hard goals are reported, and a violation is said on stdout.
  const nlohmann::json& stage = summary["results"]["tune"]["nonlinear_stage"];
  ASSERT_EQ(stage.size(), 1u);
  const bool met = stage[0]["linear_hard_goals_met"].get<bool>();
  EXPECT_EQ(met, stage[0]["final"]["linear_hard"].get<double>() <= 1.0);
  EXPECT_EQ(met, r.output.find("VIOLATE the linear hard goal") == std::string::npos) << r.output;
}

TEST(TuneCli, UnknownJointIsBadInput) {
  const Result r = runFullarm("tune --joints XX --out " + tempDir("bad").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("XX"), std::string::npos) << r.output;
}

TEST(TuneCli, ZeroRoundsIsBadInput) {
  const Result r = runFullarm("tune --rounds 0 --out " + tempDir("rounds").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--rounds"), std::string::npos) << r.output;
}

}  // namespace
