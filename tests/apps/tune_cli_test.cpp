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
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 4) << r.output;  // 4: budget ran out before verified gains
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  const fullarm::controllers::GainsConfig gains = fullarm::controllers::loadGainsConfig(dir / "gains.yaml", model);
  EXPECT_EQ(gains.joints.size(), 7u);
  // The joints not tuned are copied from the fixed start file (its SFE differs from the shipped one).
  const auto start = fullarm::controllers::loadGainsConfig(fullarm::controllers::defaultTuneStartGainsPath(), model);
  const auto sfe = [](const fullarm::controllers::GainsConfig& g) {
    return g.joints[static_cast<std::size_t>(fullarm::controllers::findGainsJoint(g, "SFE"))];
  };
  EXPECT_EQ(sfe(gains).impedance.damping_nms_per_rad, sfe(start).impedance.damping_nms_per_rad);
  EXPECT_EQ(sfe(gains).sliding_mode.boundary_layer_radps, sfe(start).sliding_mode.boundary_layer_radps);
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

// The contact goal (Eq. C6) of the written gains is reported whether or not it is hard; with
// --contact-goal a linear stage that ends feasible wrote gains that meet it (the same models).
TEST(TuneCli, ContactGoalIsReportedAndMetWhenMadeHard) {
  for (const bool hard : {false, true}) {
    const auto dir = tempDir(hard ? "eb_contact_hard" : "eb_contact_reported");
    const Result r = runFullarm("tune --joints EB --global-evals 40 --local-evals 30 --rounds 1 --nonlinear-rounds 0" +
                                std::string(hard ? " --contact-goal" : "") + " --out " + dir.string());
    ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 4) << r.output;  // 4: budget ran out before verified gains
    std::ifstream in(dir / "summary.json");
    const nlohmann::json summary = nlohmann::json::parse(in);
    const nlohmann::json& joint = summary["results"]["tune"]["joints"][0];
    const nlohmann::json& contact = joint["contact_goal"];
    ASSERT_TRUE(contact["value"].is_number()) << contact.dump();
    // A computed goal, not a default: a stable loop against the wall with an oscillatory mode.
    EXPECT_GT(contact["spectral_radius"].get<double>(), 0.5) << contact.dump();
    EXPECT_LT(contact["spectral_radius"].get<double>(), 1.5) << contact.dump();
    EXPECT_GT(contact["detector_score"].get<double>(), 0.0) << contact.dump();
    const nlohmann::json& goals = joint["tuned_goals"];
    if (hard) {
      // The written gains are the linear stage's (no nonlinear stage), judged on the same models:
      // the stage's own contact values are the reported ones, and they are part of its hard value.
      EXPECT_DOUBLE_EQ(goals["contact_spectral_radius"].get<double>(), contact["spectral_radius"].get<double>());
      EXPECT_DOUBLE_EQ(goals["contact_detector_score"].get<double>(), contact["detector_score"].get<double>());
      EXPECT_GE(goals["hard"].get<double>(), contact["value"].get<double>());
      EXPECT_EQ(joint["feasible"].get<bool>(), r.exit_code == 0);
      if (joint["feasible"].get<bool>()) {
        EXPECT_LE(contact["value"].get<double>(), 1.0) << contact.dump();
      }
    } else {
      EXPECT_EQ(goals["contact_detector_score"].get<double>(), 0.0);  // not a goal: not evaluated
      EXPECT_EQ(goals["contact_spectral_radius"].get<double>(), 0.0);
    }
  }
}

/// The gains `tune` searches, of `joint`, equal bit for bit in `a` and `b`.
void expectSameTunedGains(const fullarm::controllers::GainsConfig& a, const fullarm::controllers::GainsConfig& b,
                          const std::string& joint) {
  const auto at = [&](const fullarm::controllers::GainsConfig& g) {
    return g.joints[static_cast<std::size_t>(fullarm::controllers::findGainsJoint(g, joint))];
  };
  EXPECT_EQ(at(a).impedance.inertia_kgm2, at(b).impedance.inertia_kgm2) << joint;
  EXPECT_EQ(at(a).impedance.damping_nms_per_rad, at(b).impedance.damping_nms_per_rad) << joint;
  EXPECT_EQ(at(a).impedance.stiffness_nm_per_rad, at(b).impedance.stiffness_nm_per_rad) << joint;
  EXPECT_EQ(at(a).sliding_mode.lambda_per_s, at(b).sliding_mode.lambda_per_s) << joint;
  EXPECT_EQ(at(a).sliding_mode.boundary_layer_radps, at(b).sliding_mode.boundary_layer_radps) << joint;
}

// The arm fitted to the DTS reference's gravity torques ships with its own gains:
// config/dts_gains_reference_gravity.yaml is `fullarm tune --config
// config/dts_master_reference_gravity.yaml --nonlinear-rounds 6` (below its header). One joint
// tuned the same way writes its gains bit for bit, and `validate` passes every joint on that arm.
std::filesystem::path referenceGravityArmPath() {
  return fullarm::arm::defaultArmModelPath().parent_path() / "dts_master_reference_gravity.yaml";
}
std::filesystem::path referenceGravityGainsPath() {
  return fullarm::controllers::defaultGainsConfigPath().parent_path() / "dts_gains_reference_gravity.yaml";
}

TEST(TuneCli, OneJointOnTheReferenceGravityArmReproducesItsShippedGains) {
  const auto dir = tempDir("wr_reference_gravity");
  const Result r = runFullarm("tune --joints WR --nonlinear-rounds 6 --config " + referenceGravityArmPath().string() +
                              " --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(referenceGravityArmPath());
  const auto tuned = fullarm::controllers::loadGainsConfig(dir / "gains.yaml", model);
  const auto shipped = fullarm::controllers::loadGainsConfig(referenceGravityGainsPath(), model);
  expectSameTunedGains(tuned, shipped, "WR");
  // Tuned on the heavier arm: not the default arm's gains.
  const auto default_gains =
      fullarm::controllers::loadGainsConfig(fullarm::controllers::defaultGainsConfigPath(), model);
  bool differs = false;
  for (std::size_t j = 0; j < shipped.joints.size(); ++j) {
    differs =
        differs ||
        shipped.joints[j].impedance.damping_nms_per_rad != default_gains.joints[j].impedance.damping_nms_per_rad ||
        shipped.joints[j].sliding_mode.boundary_layer_radps !=
            default_gains.joints[j].sliding_mode.boundary_layer_radps;
  }
  EXPECT_TRUE(differs);
}

TEST(TuneCli, TheReferenceGravityArmsShippedGainsPassValidate) {
  const auto dir = tempDir("validate_reference_gravity");
  const Result r = runFullarm("validate --quiet --config " + referenceGravityArmPath().string() + " --gains " +
                              referenceGravityGainsPath().string() + " --out " + dir.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  const nlohmann::json& v = summary["results"]["validate"];
  EXPECT_TRUE(v["pass"].get<bool>());
  ASSERT_EQ(v["joints"].size(), 7u);
  for (const nlohmann::json& j : v["joints"]) {
    EXPECT_TRUE(j["pass"].get<bool>()) << j["name"];
    EXPECT_EQ(j["monte_carlo"]["samples"].get<int>(), 300) << j["name"];
    EXPECT_EQ(j["monte_carlo"]["failures"].get<int>(), 0) << j["name"];
  }
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
