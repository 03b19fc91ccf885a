// Reach sampling: every hand point within the chain's length from the shoulder, the sampled reach
// against a brute-force grid over the joint ranges, and seeded determinism.

#include "fullarm/arm/reach.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"

namespace fullarm::arm {
namespace {

using test::defaultModel;

constexpr int kSamples = 20000;
constexpr std::uint64_t kSeed = 1;
// Points per joint of the brute-force grid (range ends included).
constexpr int kGridPoints = 7;
// Both the grid (1/6 of each range apart) and 20,000 random postures come within a few
// millimetres of the true maximum; measured: grid 0.6395 m, sampled 0.6369 m.
constexpr double kReachTolerance_m = 5e-3;

// Upper bound on the shoulder-to-hand distance of any posture: the sum of the lengths of the
// fixed translations along the chain from the first joint to the hand point (triangle inequality).
double chainLength(const ArmModel& model) {
  double length = model.X_LT.translation().norm();
  for (int j = model.tool_link; j > 0; j = model.joints[static_cast<std::size_t>(j)].parent) {
    length += model.joints[static_cast<std::size_t>(j)].X_PL0.translation().norm();
  }
  return length;
}

// Largest shoulder-to-hand distance over a grid of kGridPoints per joint that moves the hand
// (the other joints at their default).
double gridReach(const ArmModel& model) {
  std::vector<int> moving;
  for (int j = 0; j < model.numJoints(); ++j) {
    if (jointMovesLink(model, j, model.tool_link)) moving.push_back(j);
  }
  ArmData data(model);
  Eigen::VectorXd q = model.defaultPosture();
  computeForwardKinematics(model, data, q);
  const Eigen::Vector3d shoulder = data.o_W[0];
  std::vector<int> index(moving.size(), 0);
  double reach = 0.0;
  while (true) {
    for (std::size_t m = 0; m < moving.size(); ++m) {
      const JointLimits& lim = model.joints[static_cast<std::size_t>(moving[m])].limits;
      q[moving[m]] = lim.min_rad + (lim.max_rad - lim.min_rad) * index[m] / (kGridPoints - 1);
    }
    computeForwardKinematics(model, data, q);
    reach = std::max(reach, (data.X_WT.translation() - shoulder).norm());
    std::size_t m = 0;
    while (m < moving.size() && ++index[m] == kGridPoints) index[m++] = 0;
    if (m == moving.size()) break;
  }
  return reach;
}

TEST(Reach, EveryHandPointLiesWithinTheChainLengthOfTheShoulder) {
  const ArmModel& model = defaultModel();
  const ReachSample r = sampleReach(model, kSamples, kSeed);
  ASSERT_EQ(r.numPostures(), kSamples);
  const double bound = chainLength(model);
  double largest = 0.0;
  for (const Eigen::Vector3d& p : r.hand_W) {
    ASSERT_TRUE(p.allFinite());
    largest = std::max(largest, (p - r.shoulder_W).norm());
  }
  EXPECT_LE(largest, bound);
  EXPECT_DOUBLE_EQ(r.reach_m, largest);
  // The shoulder centre is the first joint's origin at any posture.
  ArmData data(model);
  computeForwardKinematics(model, data, model.upperLimits());
  EXPECT_EQ(r.shoulder_W, data.o_W[0]);
}

TEST(Reach, SampledReachMatchesABruteForceGridOverTheJointRanges) {
  const ArmModel& model = defaultModel();
  const double grid = gridReach(model);
  const double sampled = sampleReach(model, kSamples, kSeed).reach_m;
  EXPECT_NEAR(sampled, grid, kReachTolerance_m);
}

TEST(Reach, TheSameSeedDrawsTheSamePosturesAndAnotherSeedOthers) {
  const ArmModel& model = defaultModel();
  const ReachSample a = sampleReach(model, 500, kSeed);
  const ReachSample b = sampleReach(model, 500, kSeed);
  const ReachSample c = sampleReach(model, 500, kSeed + 1);
  ASSERT_EQ(a.hand_W.size(), b.hand_W.size());
  for (std::size_t k = 0; k < a.hand_W.size(); ++k) EXPECT_EQ(a.hand_W[k], b.hand_W[k]) << k;
  EXPECT_EQ(a.reach_m, b.reach_m);
  std::size_t same = 0;
  for (std::size_t k = 0; k < a.hand_W.size(); ++k) same += a.hand_W[k] == c.hand_W[k] ? 1 : 0;
  EXPECT_EQ(same, 0u);
  // A shorter run draws the first postures of a longer one.
  const ReachSample first = sampleReach(model, 10, kSeed);
  for (std::size_t k = 0; k < first.hand_W.size(); ++k) EXPECT_EQ(first.hand_W[k], a.hand_W[k]) << k;
}

TEST(Reach, NoPostureGivesNoReachAndANegativeCountIsRejected) {
  const ArmModel& model = defaultModel();
  const ReachSample none = sampleReach(model, 0, kSeed);
  EXPECT_TRUE(none.hand_W.empty());
  EXPECT_EQ(none.reach_m, 0.0);
  EXPECT_THROW((void)sampleReach(model, -1, kSeed), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::arm
