// The scene-level SNCH search on the DRC valve scene (16,611 triangles: sliver-filled and open
// CAD meshes) against brute force over ALL triangles (the exact capsule links) or ALL triangle
// pairs (the links as faceted meshes) of every link and object: the same minima (feature pairs,
// distances, directions), at the benchmark posture and at a perturbed one with many contacts.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <tuple>

#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/scene.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

constexpr double kCutoff_m = 0.03;  // config/haptics.yaml

void sortByFeatures(std::vector<LocalMinimum>& v) {
  std::sort(v.begin(), v.end(), [](const LocalMinimum& a, const LocalMinimum& b) {
    return std::make_tuple(a.link, a.object, static_cast<int>(a.feature_link.kind), a.feature_link.index,
                           static_cast<int>(a.feature_object.kind), a.feature_object.index) <
           std::make_tuple(b.link, b.object, static_cast<int>(b.feature_link.kind), b.feature_link.index,
                           static_cast<int>(b.feature_object.kind), b.feature_object.index);
  });
}

// The search on `world` (the valve scene) against brute force at the reach posture and a
// perturbed one; returns the number of minima compared.
int compareWithBruteForce(const CollisionWorld& world, const Scene& scene) {
  const arm::ArmModel& model = world.model();
  const Eigen::VectorXd reach = scenePosture(scene, "reach_valve", model);
  Eigen::VectorXd perturbed = reach;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> dq(-0.15, 0.15);
  for (int i = 0; i < perturbed.size(); ++i) perturbed[i] += dq(rng);
  int total = 0;
  for (const Eigen::VectorXd& q : {reach, perturbed}) {
    arm::ArmData fk(model);
    arm::computeForwardKinematics(model, fk, q);
    std::vector<LocalMinimum> snch;
    SnchGlobalSearch search;
    search.search(world, fk, kCutoff_m, 0.0, snch);  // r = 0: every minimum
    std::vector<LocalMinimum> brute = test::bruteForceWorldMinima(world, fk, kCutoff_m);
    sortByFeatures(snch);
    sortByFeatures(brute);
    EXPECT_EQ(snch.size(), brute.size());
    if (snch.size() != brute.size()) return 0;
    for (std::size_t i = 0; i < snch.size(); ++i) {
      EXPECT_TRUE(sameFeaturePair(snch[i], brute[i])) << i;
      EXPECT_EQ(snch[i].tri_link, brute[i].tri_link);
      EXPECT_EQ(snch[i].tri_object, brute[i].tri_object);
      EXPECT_NEAR(snch[i].distance_m, brute[i].distance_m, 1e-12);
      EXPECT_NEAR((snch[i].u_W - brute[i].u_W).norm(), 0.0, 1e-9);
    }
    total += static_cast<int>(snch.size());
  }
  return total;
}

TEST(SnchValveSceneTest, GlobalSearchEqualsBruteForceOverAllTriangles) {
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  const CollisionWorld world = makeCollisionWorld(scene, arm::test::defaultModel());
  const int total = compareWithBruteForce(world, scene);
  EXPECT_GT(total, 20);  // the perturbed posture has many contacts
  RecordProperty("minima", total);
}

TEST(SnchValveSceneTest, GlobalSearchEqualsBruteForceOverAllTrianglePairsWithMeshLinks) {
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  CollisionWorld world = makeCollisionWorld(scene, arm::test::defaultModel());
  EXPECT_GE(test::facetCapsuleLinks(world, 16, 4), 3);
  const int total = compareWithBruteForce(world, scene);
  EXPECT_GT(total, 20);
  RecordProperty("minima", total);
}

}  // namespace
}  // namespace fullarm::haptics
