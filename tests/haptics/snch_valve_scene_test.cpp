// The scene-level SNCH search on the DRC valve scene (27,027 triangles: sliver-filled,
// double-sided and open CAD meshes) against brute force over ALL triangle pairs of every link
// and object: the same minima (feature pairs, distances, directions), at the benchmark posture
// and at a perturbed one with many contacts.
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

TEST(SnchValveSceneTest, GlobalSearchEqualsBruteForceOverAllTrianglePairs) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  const CollisionWorld world = makeCollisionWorld(scene, model);
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
    std::vector<LocalMinimum> brute;
    for (int l = 0; l < world.numLinks(); ++l) {
      if (!world.hasLinkMesh(l)) continue;
      for (int o = 0; o < world.numObjects(); ++o) {
        std::vector<LocalMinimum> pair = test::bruteForceMinima(world.linkMesh(l), fk.X_WL[static_cast<std::size_t>(l)],
                                                                world.object(o).mesh, world.object(o).X_WO, kCutoff_m);
        for (LocalMinimum& m : pair) {
          m.link = l;
          m.object = o;
        }
        brute.insert(brute.end(), pair.begin(), pair.end());
      }
    }
    sortByFeatures(snch);
    sortByFeatures(brute);
    ASSERT_EQ(snch.size(), brute.size());
    for (std::size_t i = 0; i < snch.size(); ++i) {
      EXPECT_TRUE(sameFeaturePair(snch[i], brute[i])) << i;
      EXPECT_EQ(snch[i].tri_link, brute[i].tri_link);
      EXPECT_EQ(snch[i].tri_object, brute[i].tri_object);
      EXPECT_NEAR(snch[i].distance_m, brute[i].distance_m, 1e-12);
      EXPECT_NEAR((snch[i].u_W - brute[i].u_W).norm(), 0.0, 1e-9);
    }
    total += static_cast<int>(snch.size());
  }
  EXPECT_GT(total, 20);  // the perturbed posture has many contacts
  RecordProperty("minima", total);
}

}  // namespace
}  // namespace fullarm::haptics
