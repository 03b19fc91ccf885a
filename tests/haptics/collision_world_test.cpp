// Scene-level global search: every arm link x every object at a real arm configuration equals
// brute force over every triangle (capsule links) or every triangle pair (mesh links) of every
// link/object pair, with link/object indices set, and the pruned result is the pruning of that
// set.
#include "fullarm/haptics/collision_world.hpp"

#include <gtest/gtest.h>

#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

// The search of `world` against brute force at 4 random configurations with two objects
// near the forearm and the hand; returns the number of minima compared.
int compareWithBruteForce(const CollisionWorld& world) {
  const arm::ArmModel& model = world.model();
  arm::ArmData fk(model);
  std::mt19937 rng(77);
  int total = 0;
  for (int trial = 0; trial < 4; ++trial) {
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
    std::vector<LocalMinimum> brute = test::bruteForceWorldMinima(w, fk, kCutoff);
    EXPECT_EQ(snch.size(), brute.size()) << "trial " << trial;
    if (snch.size() != brute.size()) return 0;
    for (const auto& m : snch) {
      const auto it =
          std::find_if(brute.begin(), brute.end(), [&](const LocalMinimum& b) { return sameFeaturePair(b, m); });
      EXPECT_NE(it, brute.end());
      if (it == brute.end()) return 0;
      EXPECT_NEAR(it->distance_m, m.distance_m, 1e-12);
      // Endpoints in the local frames map to world points the reported distance apart (a
      // capsule's point lies beyond the object's when the capsule reaches into it).
      const double gap = (fk.X_WL[static_cast<std::size_t>(m.link)] * m.p_L - w.object(m.object).X_WO * m.p_O).norm();
      if (m.distance_m > 0.0 || w.linkShape(m.link) == LinkShape::kMesh) {
        EXPECT_NEAR(gap, m.distance_m, 1e-12);
      }
    }
    total += static_cast<int>(snch.size());
    // Pruned search = pruning of the full set.
    std::vector<LocalMinimum> pruned;
    w.globalSearch(fk, kCutoff, 0.02, pruned);
    pruneMinima(brute, 0.02);
    EXPECT_EQ(pruned.size(), brute.size());
    if (pruned.size() != brute.size()) return 0;
    for (std::size_t i = 0; i < pruned.size(); ++i) EXPECT_TRUE(sameFeaturePair(pruned[i], brute[i]));
  }
  return total;
}

TEST(CollisionWorldTest, CapsuleLinksAreQueriedAsExactCapsules) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const CollisionWorld world(model);
  int capsules = 0;
  for (int l = 0; l < world.numLinks(); ++l) {
    const arm::LinkGeometry& g = model.joints[static_cast<std::size_t>(l)].geometry;
    EXPECT_EQ(world.linkShape(l) == LinkShape::kCapsule, g.type == arm::LinkGeometry::Type::kCapsule) << l;
    if (world.linkShape(l) != LinkShape::kCapsule) continue;
    ++capsules;
    EXPECT_EQ(world.linkCapsule(l).a_m, g.from_m);
    EXPECT_EQ(world.linkCapsule(l).b_m, g.to_m);
    EXPECT_EQ(world.linkCapsule(l).radius_m, g.radius_m);
    EXPECT_FALSE(world.hasLinkMesh(l));
    EXPECT_TRUE(world.hasLinkGeometry(l));
  }
  EXPECT_GE(capsules, 3);  // upper arm, forearm, hand (+ fingers)
}

TEST(CollisionWorldTest, GlobalSearchEqualsBruteForceOverAllLinkObjectPairs) {
  const CollisionWorld world(arm::test::defaultModel());
  EXPECT_GT(compareWithBruteForce(world), 5);
}

TEST(CollisionWorldTest, GlobalSearchEqualsBruteForceWithMeshLinks) {
  CollisionWorld world(arm::test::defaultModel());
  EXPECT_GE(test::facetCapsuleLinks(world, 8, 2), 3);
  EXPECT_GT(compareWithBruteForce(world), 5);
}

}  // namespace
}  // namespace fullarm::haptics
