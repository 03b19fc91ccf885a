// The human arm file: strict reading with clear errors, the torque limits and their posture
// factors, and g_human(q) against finite differences of the segments' potential energy.

#include "fullarm/accessibility/human_strength.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "arm_test_util.hpp"
#include "config_text.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"

namespace fullarm::accessibility {
namespace {

using arm::test::defaultModel;
using testing::expectConfigError;
using testing::fileText;
using testing::replacedFirst;

constexpr double kDeg = std::numbers::pi / 180.0;

const std::string& shippedText() {
  static const std::string text = fileText(arm::test::sourcePath("config/human_arm.yaml"));
  return text;
}

HumanArm parse(const std::string& text) { return parseHumanArm(text, "human_arm_test.yaml", defaultModel()); }

const JointStrength& strengthOf(const HumanArm& human, const char* name) {
  const int j = defaultModel().jointIndex(name);
  for (const JointStrength& s : human.joints) {
    if (s.joint == j) return s;
  }
  ADD_FAILURE() << name << " not in the human arm";
  return human.joints.front();
}

TEST(HumanStrength, ShippedFileCoversTheArmJointsWithElbowFlexionStrongerThanExtension) {
  const HumanArm human = loadHumanArm(defaultHumanArmPath(), defaultModel());
  ASSERT_EQ(static_cast<int>(human.joints.size()), defaultModel().numArmJoints());
  for (std::size_t i = 0; i < human.joints.size(); ++i) EXPECT_EQ(human.joints[i].joint, static_cast<int>(i));
  const JointStrength& elbow = strengthOf(human, "R_EB");
  EXPECT_EQ(elbow.positive.action, "elbow flexion");
  EXPECT_GT(elbow.positive.torque_nm, elbow.negative.torque_nm);
  EXPECT_EQ(human.segments.size(), 3U);
  EXPECT_DOUBLE_EQ(human.strength_scale, 1.0);
}

TEST(HumanStrength, LimitsFollowThePostureFactorsAndTheStrengthScale) {
  HumanArm human = parse(shippedText());
  const arm::ArmModel& model = defaultModel();
  Eigen::VectorXd q = model.defaultPosture();
  const int sfe = model.jointIndex("R_SFE");
  Eigen::VectorXd lo;
  Eigen::VectorXd hi;
  // Shoulder flexion: 89.9 N m at 0 deg, 68.6 N m at 45 deg (the figures the factor encodes),
  // linear between, constant beyond.
  q[sfe] = 0.0;
  computeTorqueLimits(human, q, lo, hi);
  EXPECT_NEAR(hi[sfe], 89.9, 1e-9);
  EXPECT_NEAR(lo[sfe], -112.4, 1e-9);  // extension has no posture factor
  q[sfe] = 45.0 * kDeg;
  computeTorqueLimits(human, q, lo, hi);
  EXPECT_NEAR(hi[sfe], 89.9 * 0.763, 1e-9);
  q[sfe] = 22.5 * kDeg;
  computeTorqueLimits(human, q, lo, hi);
  EXPECT_NEAR(hi[sfe], 89.9 * (1.0 + 0.763) / 2.0, 1e-9);
  q[sfe] = 70.0 * kDeg;
  computeTorqueLimits(human, q, lo, hi);
  EXPECT_NEAR(hi[sfe], 89.9 * 0.763, 1e-9);
  // Elbow flexion reads the forearm rotation: full supination 1, full pronation 0.525.
  const int eb = model.jointIndex("R_EB");
  const int wr = model.jointIndex("R_WR");
  q[wr] = 84.0 * kDeg;
  computeTorqueLimits(human, q, lo, hi);
  EXPECT_NEAR(hi[eb], 79.5, 1e-9);
  q[wr] = -84.0 * kDeg;
  computeTorqueLimits(human, q, lo, hi);
  EXPECT_NEAR(hi[eb], 79.5 * 0.525, 1e-9);
  human.strength_scale = 0.5;
  computeTorqueLimits(human, q, lo, hi);
  EXPECT_NEAR(hi[eb], 0.5 * 79.5 * 0.525, 1e-9);
  EXPECT_NEAR(lo[eb], -0.5 * 60.5, 1e-9);
}

TEST(HumanStrength, GravityTorquesAreTheGradientOfTheSegmentsPotentialEnergy) {
  const arm::ArmModel& model = defaultModel();
  const HumanArm human = parse(shippedText());
  arm::ArmData fk(model);
  auto potential = [&](const Eigen::VectorXd& q) {
    arm::computeForwardKinematics(model, fk, q);
    double v = 0.0;
    for (const HumanSegment& s : human.segments) {
      int link = -1;
      const Eigen::Vector3d p_L = segmentCom(model, s, link);
      v -= s.mass_fraction * human.body_mass_kg * model.gravity_W_mps2.dot(arm::pointInWorld(fk, link, p_L));
    }
    return v;
  };
  std::mt19937 rng(7);
  constexpr double kStep = 1e-6;
  constexpr double kTolerance_nm = 1e-6;
  for (int trial = 0; trial < 5; ++trial) {
    const Eigen::VectorXd q = arm::test::randomConfiguration(model, rng);
    arm::computeForwardKinematics(model, fk, q);
    const Eigen::VectorXd g = computeHumanGravityTorques(model, human, fk);
    for (int j = 0; j < model.numJoints(); ++j) {
      Eigen::VectorXd qp = q;
      Eigen::VectorXd qm = q;
      qp[j] += kStep;
      qm[j] -= kStep;
      const double fd = (potential(qp) - potential(qm)) / (2.0 * kStep);
      EXPECT_NEAR(g[j], fd, kTolerance_nm) << "joint " << j << " trial " << trial;
    }
  }
}

TEST(HumanStrength, SegmentCentresOfMassLieOnTheArmModelsSegments) {
  const arm::ArmModel& model = defaultModel();
  const HumanArm human = parse(shippedText());
  int link = -1;
  // Upper arm: link of R_HR, proximal end at z = -d (0.287 m), 43.6 % of the way to its origin.
  const Eigen::Vector3d upper = segmentCom(model, human.segments[0], link);
  EXPECT_EQ(link, model.upper_arm_joint);
  EXPECT_NEAR(upper.z(), -0.287 * (1.0 - 0.436), 1e-12);
  const Eigen::Vector3d hand = segmentCom(model, human.segments[2], link);
  EXPECT_EQ(link, model.tool_link);
  EXPECT_NEAR((hand - 0.506 * model.X_LT.translation()).norm(), 0.0, 1e-12);
}

TEST(HumanStrength, BadFilesGetErrorsNamingFileKeyAndValue) {
  const std::string& text = shippedText();
  const char* source = "human_arm_test.yaml";
  expectConfigError([&] { (void)parse(replacedFirst(text, "name: R_SFE", "name: R_XYZ")); }, source,
                    "joints[0].name", "R_XYZ");
  expectConfigError([&] { (void)parse(replacedFirst(text, "torque_nm: 89.9", "torque_nm: -3")); }, source,
                    "joints[0].positive.torque_nm", "-3");
  expectConfigError([&] { (void)parse(replacedFirst(text, "angle_deg: [0.0, 45.0]", "angle_deg: [45.0, 0.0]")); },
                    source, "angle_deg", "increasing");
  expectConfigError([&] { (void)parse(replacedFirst(text, "factor: [1.0, 0.763]", "factor: [1.0]")); }, source,
                    "factor", "one per angle_deg");
  expectConfigError([&] { (void)parse(replacedFirst(text, "strength_scale: 1.0", "strength_scale: 0")); }, source,
                    "strength_scale", "> 0");
  expectConfigError([&] { (void)parse(replacedFirst(text, "along: forearm", "along: shin")); }, source,
                    "segments[1].along", "shin");
  expectConfigError([&] { (void)parse(replacedFirst(text, "body_mass_kg: 80.0", "body_mass_kg: 80.0\ncolour: red")); },
                    source, "colour", "");
  expectConfigError([&] { (void)parse(replacedFirst(text, "name: R_SAA", "name: R_SFE")); }, source,
                    "joints[1].name", "twice");
}

}  // namespace
}  // namespace fullarm::accessibility
