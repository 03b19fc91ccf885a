// Inverse kinematics over the arm's redundancy, checked against forward kinematics.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fullarm/accessibility/ik.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"

namespace fullarm::accessibility {
namespace {

arm::ArmModel model() {
  return arm::loadArmModel(arm::defaultArmModelPath());
}

// A pose reached by a known configuration is solved again from another seed, at the known
// configuration's swivel angle: forward kinematics of the answer gives the pose back.
TEST(IkTest, SolvesAPoseOfForwardKinematicsFromAnotherSeed) {
  const arm::ArmModel m = model();
  arm::ArmData fk(m);
  Eigen::VectorXd q = m.defaultPosture();
  q.head<7>() << 0.9, -0.4, 0.3, 1.2, 0.2, 0.1, -0.1;
  arm::computeForwardKinematics(m, fk, q);
  const Eigen::Vector3d p = fk.X_WT.translation();
  const Eigen::Matrix3d R = fk.X_WL[static_cast<std::size_t>(m.tool_link)].linear();
  const double swivel = swivelAngle(fk);
  Eigen::VectorXd seed = m.defaultPosture();
  seed.head<7>() << 0.5, -0.2, 0.0, 1.0, 0.0, 0.0, 0.0;
  const IkSolution sol = solveIk(m, fk, p, R, swivel, seed, IkOptions{});
  ASSERT_TRUE(sol.converged);
  arm::computeForwardKinematics(m, fk, sol.q_rad);
  EXPECT_LT((fk.X_WT.translation() - p).norm(), 1e-4);
  EXPECT_LT(Eigen::AngleAxisd(fk.X_WL[static_cast<std::size_t>(m.tool_link)].linear() * R.transpose()).angle(), 1e-3);
  EXPECT_LT(std::abs(std::remainder(swivelAngle(fk) - swivel, 2.0 * std::numbers::pi)), 1e-3);
}

// The swivel angle is the elbow's angle about the shoulder-wrist line: moving the elbow by the
// self-motion (one solve at swivel + 0.3 rad) leaves the hand where it was and turns the elbow
// by 0.3 rad about the line, measured here from the elbow positions directly.
TEST(IkTest, SwivelAngleTurnsTheElbowAboutTheShoulderWristLine) {
  const arm::ArmModel m = model();
  arm::ArmData fk(m);
  Eigen::VectorXd q = m.defaultPosture();
  q.head<7>() << 0.9, -0.4, 0.3, 1.2, 0.2, 0.1, -0.1;
  arm::computeForwardKinematics(m, fk, q);
  const Eigen::Vector3d p = fk.X_WT.translation();
  const Eigen::Matrix3d R = fk.X_WL[static_cast<std::size_t>(m.tool_link)].linear();
  const Eigen::Vector3d s = fk.o_W[0];
  const Eigen::Vector3d w = fk.o_W[5];
  const Eigen::Vector3d n = (w - s).normalized();
  const Eigen::Vector3d e0 = fk.o_W[3] - s;
  const IkSolution sol = solveIk(m, fk, p, R, swivelAngle(fk) + 0.3, q, IkOptions{});
  ASSERT_TRUE(sol.converged);
  arm::computeForwardKinematics(m, fk, sol.q_rad);
  EXPECT_LT((fk.o_W[5] - w).norm(), 1e-3);  // the wrist stays (the hand pose fixes it)
  const Eigen::Vector3d e1 = fk.o_W[3] - s;
  const Eigen::Vector3d a = (e0 - e0.dot(n) * n).normalized();
  const Eigen::Vector3d b = (e1 - e1.dot(n) * n).normalized();
  EXPECT_NEAR(std::atan2(n.dot(a.cross(b)), a.dot(b)), 0.3, 2e-3);
}

// Every solution of a sweep is within the joint limits and puts the hand on the target.
TEST(IkTest, SweepSolutionsRespectLimitsAndReachTheTarget) {
  const arm::ArmModel m = model();
  arm::ArmData fk(m);
  GraspTarget t;
  t.position_W_m = m.X_WB.translation() + Eigen::Vector3d(0.0, 0.50, -0.15);
  t.approach_W = Eigen::Vector3d::UnitY();
  IkOptions o;
  o.swivel_samples = 24;
  o.roll_samples = 6;
  const std::vector<IkSolution> goals = sweepGoalConfigurations(m, t, m.defaultPosture(), o);
  ASSERT_GT(goals.size(), 5u);
  const Eigen::VectorXd lo = m.lowerLimits();
  const Eigen::VectorXd hi = m.upperLimits();
  for (const IkSolution& g : goals) {
    EXPECT_TRUE((g.q_rad.array() >= lo.array()).all() && (g.q_rad.array() <= hi.array()).all());
    arm::computeForwardKinematics(m, fk, g.q_rad);
    EXPECT_LT((fk.X_WT.translation() - t.position_W_m).norm(), 1e-4);
    EXPECT_LT((fk.X_WL[static_cast<std::size_t>(m.tool_link)].linear().col(0) - t.approach_W).norm(), 2e-3);
  }
}

// A target beyond the arm's reach has no solution.
TEST(IkTest, TargetBeyondReachHasNoSolution) {
  const arm::ArmModel m = model();
  GraspTarget t;
  t.position_W_m = m.X_WB.translation() + Eigen::Vector3d(0.0, 0.90, 0.0);
  t.approach_W = Eigen::Vector3d::UnitY();
  IkOptions o;
  o.swivel_samples = 12;
  o.roll_samples = 4;
  EXPECT_TRUE(sweepGoalConfigurations(m, t, m.defaultPosture(), o).empty());
}

}  // namespace
}  // namespace fullarm::accessibility
