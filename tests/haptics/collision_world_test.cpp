// Scene-level global search: every arm link x every object at a real arm configuration equals
// brute force over all triangle pairs of every link/object pair, with link/object indices set,
// and the pruned result is the pruning of that set.
#include "fullarm/haptics/collision_world.hpp"

#include <gtest/gtest.h>

#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

TEST(CollisionWorldTest, GlobalSearchEqualsBruteForceOverAllLinkObjectPairs) {
  const arm::ArmModel& model = arm::test::defaultModel();
  CollisionWorld world(model, {8, 2});
  int links_with_mesh = 0;
  for (int l = 0; l < world.numLinks(); ++l) links_with_mesh += world.hasLinkMesh(l) ? 1 : 0;
  EXPECT_GE(links_with_mesh, 3);  // upper arm, forearm, hand (+ fingers)
  arm::ArmData fk(model);
  std::mt19937 rng(77);
  int total = 0;
  for (int trial = 0; trial < 6; ++trial) {
    arm::computeForwardKinematics(model, fk, arm::test::randomConfiguration(model, rng));
    // Objects around the forearm and the hand, within a few centimetres.
    CollisionWorld w = world;
    const Eigen::Vector3d p4 = fk.X_WL[4].translation();
    const Eigen::Vector3d p6 = fk.X_WL[6].translation();
    Eigen::Isometry3d X1 = test::randomPose(rng, 0.0);
    X1.translation() = p4 + Eigen::Vector3d(0.0, 0.0, -0.12);
    Eigen::Isometry3d X2 = test::randomPose(rng, 0.0);
    X2.translation() = p6 + Eigen::Vector3d(0.08, 0.0, 0.0);
    w.addObject("beam", makeIBeam(0.1, 0.08, 0.015, 0.01, 0.5, 0.05), X1);
    w.addObject("frame", makeRectangularFrame(0.3, 0.25, 0.05, 0.04, 0.05), X2);
    constexpr double kCutoff = 0.08;
    std::vector<LocalMinimum> snch;
    w.globalSearch(fk, kCutoff, 0.0, snch);
    std::vector<LocalMinimum> brute;
    for (int l = 0; l < w.numLinks(); ++l) {
      if (!w.hasLinkMesh(l)) continue;
      for (int o = 0; o < w.numObjects(); ++o) {
        auto pair = test::bruteForceMinima(w.linkMesh(l), fk.X_WL[static_cast<std::size_t>(l)], w.object(o).mesh,
                                           w.object(o).X_WO, kCutoff);
        for (auto& m : pair) {
          m.link = l;
          m.object = o;
        }
        brute.insert(brute.end(), pair.begin(), pair.end());
      }
    }
    ASSERT_EQ(snch.size(), brute.size()) << "trial " << trial;
    for (const auto& m : snch) {
      const auto it =
          std::find_if(brute.begin(), brute.end(), [&](const LocalMinimum& b) { return sameFeaturePair(b, m); });
      ASSERT_NE(it, brute.end());
      EXPECT_NEAR(it->distance_m, m.distance_m, 1e-12);
      // Endpoints in the local frames map to world points the reported distance apart.
      EXPECT_NEAR((fk.X_WL[static_cast<std::size_t>(m.link)] * m.p_L - w.object(m.object).X_WO * m.p_O).norm(),
                  m.distance_m, 1e-12);
    }
    total += static_cast<int>(snch.size());
    // Pruned search = pruning of the full set.
    std::vector<LocalMinimum> pruned;
    w.globalSearch(fk, kCutoff, 0.02, pruned);
    pruneMinima(brute, 0.02);
    ASSERT_EQ(pruned.size(), brute.size());
    for (std::size_t i = 0; i < pruned.size(); ++i) EXPECT_TRUE(sameFeaturePair(pruned[i], brute[i]));
  }
  EXPECT_GT(total, 5);
}

}  // namespace
}  // namespace fullarm::haptics
