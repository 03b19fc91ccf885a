// The arm-level validation pipeline (design::validateArm): each joint's linear checks and every
// Monte-Carlo run equal the same scenario analysed and simulated here one run at a time, the
// verdicts follow the runs, the results depend neither on the thread count nor on the other
// joints, the paper's claim is measured only where asked, and bad input names the joint.

#include <gtest/gtest.h>

#include <string>

#include "design_fixture.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/random.hpp"
#include "fullarm/design/validate_arm.hpp"

namespace fullarm::design {
namespace {

ValidationConfig smallConfig(int samples) {
  ValidationConfig c = loadValidationConfig(defaultValidationConfigPath());
  c.samples = samples;
  return c;
}

ArmValidationOptions jointsOn(std::vector<std::string> joints, int threads) {
  ArmValidationOptions o;
  o.joints = std::move(joints);
  o.threads = threads;
  return o;
}

TEST(ValidateArm, EachJointIsItsLinearChecksAndItsRunsSimulatedOneByOne) {
  const ValidationConfig config = smallConfig(6);
  const ArmValidationResult out =
      validateArm(test::dtsModel(), test::dtsPlant(), test::dtsGains(), config, jointsOn({"EB", "WR"}, 2));
  ASSERT_EQ(out.joints.size(), 2u);
  EXPECT_EQ(out.threads, 2);
  EXPECT_EQ(out.gains_source, test::dtsGains().source);
  bool all = true;
  for (const JointValidationResult& j : out.joints) {
    const std::string& name = j.nominal.joint_name;
    // The scenario, by hand: the gains file's joint with the validation file's user and wall.
    JointScenario sc = makeJointScenario(test::dtsModel(), test::dtsPlant(), test::dtsGains(), name);
    sc.load.inertia_kgm2 += config.user.inertia_kgm2 - sc.user.inertia_kgm2;
    sc.user = config.user;
    sc.wall = config.wall;
    sc.oscillation_speed_radps = config.oscillation_speed_radps;
    EXPECT_EQ(j.nominal.load.inertia_kgm2, sc.load.inertia_kgm2) << name;
    const ScenarioLinearResult linear =
        analyzeScenario(sc, config.linear, config.ranges.delay_max_samples, {0.0, 0.5, 1.0, 2.0, 5.0, 10.0});
    EXPECT_EQ(j.linear.pass, linear.pass) << name;
    EXPECT_EQ(j.linear.free.spectral_radius, linear.free.spectral_radius) << name;
    EXPECT_EQ(j.linear.contact_spectral_radius, linear.contact_spectral_radius) << name;
    ASSERT_EQ(j.linear.z_width.size(), linear.z_width.size()) << name;
    // Every run: its own draw of the joint's stream, simulated here.
    ASSERT_EQ(j.monte_carlo.runs.size(), 6u) << name;
    int failures = 0;
    for (int i = 0; i < 6; ++i) {
      const ModelVariation v = drawVariation(config.ranges, config.seed, core::nameSlot(name), i);
      const ClosedLoopResult r = simulateJoint(variationScenario(sc, v));
      const MonteCarloRun& run = j.monte_carlo.runs[static_cast<std::size_t>(i)];
      EXPECT_EQ(run.sample.user_stiffness_nm_per_rad, v.user_stiffness_nm_per_rad) << name << " run " << i;
      EXPECT_EQ(run.result.acceptable(), r.acceptable()) << name << " run " << i;
      EXPECT_EQ(run.result.free_rms_user_torque_nm, r.free_rms_user_torque_nm) << name << " run " << i;
      EXPECT_EQ(run.result.contact_hold_speed_rms_radps, r.contact_hold_speed_rms_radps) << name << " run " << i;
      failures += r.acceptable() ? 0 : 1;
    }
    EXPECT_EQ(j.monte_carlo.failures, failures) << name;
    // The worst run is simulated again with its trace: the same run.
    const MonteCarloRun& worst = j.monte_carlo.runs[static_cast<std::size_t>(j.monte_carlo.worst)];
    EXPECT_EQ(j.worst_result.free_rms_user_torque_nm, worst.result.free_rms_user_torque_nm) << name;
    EXPECT_FALSE(j.worst_trace.t_s.empty()) << name;
    EXPECT_EQ(j.pass, linear.pass && failures == 0) << name;
    EXPECT_EQ(j.verdict == "pass", j.pass) << j.verdict;
    EXPECT_FALSE(j.has_claim);
    all = all && j.pass;
  }
  EXPECT_EQ(out.pass(), all);
}

TEST(ValidateArm, AJointsResultsDependNeitherOnTheThreadCountNorOnTheOtherJoints) {
  const ValidationConfig config = smallConfig(4);
  const ArmValidationResult alone =
      validateArm(test::dtsModel(), test::dtsPlant(), test::dtsGains(), config, jointsOn({"R_WR"}, 1));
  const ArmValidationResult three =
      validateArm(test::dtsModel(), test::dtsPlant(), test::dtsGains(), config, jointsOn({"HR", "WR", "EB"}, 3));
  ASSERT_EQ(three.joints.size(), 3u);
  const JointValidationResult& a = alone.joints[0];
  const JointValidationResult& b = three.joints[1];
  ASSERT_EQ(b.nominal.joint_name, "R_WR");
  for (std::size_t i = 0; i < a.monte_carlo.runs.size(); ++i) {
    EXPECT_EQ(a.monte_carlo.runs[i].sample.bulk_modulus_scale, b.monte_carlo.runs[i].sample.bulk_modulus_scale);
    EXPECT_EQ(a.monte_carlo.runs[i].result.free_rms_user_torque_nm,
              b.monte_carlo.runs[i].result.free_rms_user_torque_nm);
    EXPECT_EQ(a.monte_carlo.runs[i].severity, b.monte_carlo.runs[i].severity);
  }
  EXPECT_EQ(a.verdict, b.verdict);
  EXPECT_EQ(a.linear.predicted_gain_limit, b.linear.predicted_gain_limit);
}

// Gains far beyond the linear stability limit: the joint fails, and its verdict says why (the
// linear reason and the worst failed run with its drawn values).
TEST(ValidateArm, AnUnstableJointFailsWithTheReasonAndItsWorstRun) {
  controllers::GainsConfig gains = test::dtsGains();
  controllers::JointGains& eb = gains.joints[static_cast<std::size_t>(controllers::findGainsJoint(gains, "EB"))];
  eb.sliding_mode.boundary_layer_radps /= 40.0;  // B_o/eps x 40
  const ArmValidationResult out =
      validateArm(test::dtsModel(), test::dtsPlant(), gains, smallConfig(3), jointsOn({"EB", "WR"}, 2));
  const JointValidationResult& j = out.joints[0];
  ASSERT_EQ(j.nominal.joint_name, "R_EB");
  EXPECT_FALSE(j.linear.pass);
  EXPECT_GT(j.monte_carlo.failures, 0);
  EXPECT_FALSE(j.pass);
  EXPECT_FALSE(out.pass());
  EXPECT_NE(j.verdict.find("linear: unstable"), std::string::npos) << j.verdict;
  const MonteCarloRun& worst = j.monte_carlo.runs[static_cast<std::size_t>(j.monte_carlo.worst)];
  EXPECT_NE(j.verdict.find("worst run #" + std::to_string(worst.sample.index) + " (" + describeVariation(worst.sample) +
                           "): " + worst.result.failure),
            std::string::npos)
      << j.verdict;
}

TEST(ValidateArm, ThePapersClaimIsMeasuredOnlyWhereAsked) {
  ArmValidationOptions o = jointsOn({"EB", "WR"}, 2);
  o.paper_claim = true;
  o.paper_claim_joints = {"WR"};
  const ArmValidationResult out = validateArm(test::dtsModel(), test::dtsPlant(), test::dtsGains(), smallConfig(1), o);
  EXPECT_FALSE(out.joints[0].has_claim);
  ASSERT_TRUE(out.joints[1].has_claim);
  EXPECT_EQ(out.joints[1].claim.joint_name, "R_WR");
  EXPECT_GT(out.joints[1].claim.simulations, 0);
}

TEST(ValidateArm, AnUnknownJointIsAConfigError) {
  try {
    (void)validateArm(test::dtsModel(), test::dtsPlant(), test::dtsGains(), smallConfig(1), jointsOn({"XX"}, 1));
    ADD_FAILURE() << "an unknown joint was validated";
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("XX"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fullarm::design
