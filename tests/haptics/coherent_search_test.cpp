// Coherent and parallel global searches against the fresh sequential one over the whole recorded
// motion (scenes/valve_wall_approach.csv: 1,001 postures through the valve scene's opening to the
// wheel and back): at every posture the same minima, in the same order, bit for bit (feature
// pairs, triangles, points, distances, directions). On the valve scene, on the valve scene
// subdivided once (66,444 triangles: deeper fronts), and with the links as faceted meshes (the
// two-tree path, parallel only). Also: the coherence survives a world that changes between
// searches (a new revision starts over) and a cutoff that changes.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/mesh_subdivision.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/scene.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

constexpr double kCutoff_m = 0.03;       // config/haptics.yaml
constexpr double kPruneRadius_m = 0.02;  // config/haptics.yaml

std::vector<Eigen::VectorXd> loadMotion(const arm::ArmModel& model) {
  std::ifstream in(arm::test::sourcePath("scenes/valve_wall_approach.csv"));
  std::vector<Eigen::VectorXd> motion;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::istringstream row(line);
    std::string cell;
    std::getline(row, cell, ',');
    Eigen::VectorXd q = model.defaultPosture();
    for (int j = 0; std::getline(row, cell, ','); ++j) q[j] = std::stod(cell);
    motion.push_back(q);
  }
  return motion;
}

void expectBitForBit(const std::vector<LocalMinimum>& fresh, const std::vector<LocalMinimum>& other,
                     const std::string& what) {
  ASSERT_EQ(fresh.size(), other.size()) << what;
  for (std::size_t i = 0; i < fresh.size(); ++i) {
    const LocalMinimum& a = fresh[i];
    const LocalMinimum& b = other[i];
    ASSERT_TRUE(a.link == b.link && a.object == b.object && sameFeaturePair(a, b) && a.tri_link == b.tri_link &&
                a.tri_object == b.tri_object && a.p_L == b.p_L && a.p_O == b.p_O && a.distance_m == b.distance_m &&
                a.u_W == b.u_W)
        << what << ", minimum " << i;
  }
}

struct Counts {
  long minima = 0;
  long postures_with_contact = 0;  // a minimum closer than d_f = 10 mm
  long kept = 0;                   // front nodes the coherent search kept without a test
  long rebuilds = 0;
};

// Replays the motion on `world` with the fresh sequential search and with each other variant,
// comparing at every posture.
Counts replayAndCompare(const CollisionWorld& world, const std::vector<Eigen::VectorXd>& motion, bool coherent) {
  const arm::ArmModel& model = world.model();
  SnchGlobalSearch fresh(SnchSearchOptions{1, false});
  SnchGlobalSearch coherent_1(SnchSearchOptions{1, true});
  SnchGlobalSearch parallel(SnchSearchOptions{2, false});
  SnchGlobalSearch coherent_2(SnchSearchOptions{2, true});
  arm::ArmData fk(model);
  std::vector<LocalMinimum> a;
  std::vector<LocalMinimum> b;
  Counts counts;
  for (std::size_t k = 0; k < motion.size(); ++k) {
    arm::computeForwardKinematics(model, fk, motion[k]);
    fresh.search(world, fk, kCutoff_m, kPruneRadius_m, a);
    const std::string at = "posture " + std::to_string(k);
    parallel.search(world, fk, kCutoff_m, kPruneRadius_m, b);
    expectBitForBit(a, b, "2 threads, " + at);
    if (coherent) {
      coherent_1.search(world, fk, kCutoff_m, kPruneRadius_m, b);
      expectBitForBit(a, b, "coherent, " + at);
      counts.kept += coherent_1.lastStats().coherence_kept;
      counts.rebuilds += coherent_1.lastStats().coherence_rebuilds;
      coherent_2.search(world, fk, kCutoff_m, kPruneRadius_m, b);
      expectBitForBit(a, b, "coherent on 2 threads, " + at);
    }
    if (::testing::Test::HasFatalFailure()) return counts;
    counts.minima += static_cast<long>(a.size());
    bool contact = false;
    for (const LocalMinimum& m : a) contact = contact || m.distance_m < 0.01;
    counts.postures_with_contact += contact ? 1 : 0;
  }
  return counts;
}

TEST(CoherentSearchTest, CoherentAndParallelSearchesEqualTheFreshSearchOverTheRecordedMotion) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const std::vector<Eigen::VectorXd> motion = loadMotion(model);
  ASSERT_EQ(motion.size(), 1001U);
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  const CollisionWorld world = makeCollisionWorld(scene, model);
  const Counts c = replayAndCompare(world, motion, true);
  std::cout << c.minima << " minima over the motion, " << c.postures_with_contact << " postures in contact, " << c.kept
            << " front nodes kept, " << c.rebuilds << " rebuilds\n";
  // The motion enters and leaves contacts, and the coherence was exercised.
  EXPECT_GT(c.postures_with_contact, 200);
  EXPECT_LT(c.postures_with_contact, 800);
  EXPECT_GT(c.kept, 10 * static_cast<long>(motion.size()));
  EXPECT_GT(c.rebuilds, 40);  // every pair at least once
}

TEST(CoherentSearchTest, CoherentAndParallelSearchesEqualTheFreshSearchOnTheSubdividedScene) {
  const arm::ArmModel& model = arm::test::defaultModel();
  std::vector<Eigen::VectorXd> motion = loadMotion(model);
  Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  for (SceneObject& o : scene.objects) o.mesh = subdivideMidpoint(o.mesh, 1);
  const CollisionWorld world = makeCollisionWorld(scene, model);
  // Every other posture (20 ms apart: larger steps for the fronts).
  std::vector<Eigen::VectorXd> every_other;
  for (std::size_t k = 0; k < motion.size(); k += 2) every_other.push_back(motion[k]);
  const Counts c = replayAndCompare(world, every_other, true);
  EXPECT_GT(c.postures_with_contact, 100);
  EXPECT_GT(c.kept, 10 * static_cast<long>(every_other.size()));
}

TEST(CoherentSearchTest, ParallelSearchEqualsTheFreshSearchWithMeshLinks) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const std::vector<Eigen::VectorXd> motion = loadMotion(model);
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  CollisionWorld world = makeCollisionWorld(scene, model);
  test::facetCapsuleLinks(world, 16, 4);
  // Every tenth posture (the two-tree path is slower).
  std::vector<Eigen::VectorXd> some;
  for (std::size_t k = 0; k < motion.size(); k += 10) some.push_back(motion[k]);
  const Counts c = replayAndCompare(world, some, true);
  EXPECT_GT(c.postures_with_contact, 20);
}

TEST(CoherentSearchTest, AChangedWorldOrCutoffStartsOver) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const std::vector<Eigen::VectorXd> motion = loadMotion(model);
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  CollisionWorld world = makeCollisionWorld(scene, model);
  SnchGlobalSearch coherent(SnchSearchOptions{2, true});
  arm::ArmData fk(model);
  std::vector<LocalMinimum> a;
  std::vector<LocalMinimum> b;
  std::mt19937 rng(5);
  for (std::size_t k = 300; k < 700; k += 5) {
    arm::computeForwardKinematics(model, fk, motion[k]);
    if (k == 400) {
      // A box appears beside the wheel: a new revision; the fronts of the old world must not
      // hide it.
      const std::uint64_t before = world.revision();
      world.addObject("box", makeBox({0.05, 0.05, 0.05}, 0.01),
                      world.object(world.objectIndex("wheel_valve")).X_WO * Eigen::Translation3d(0.0, 0.0, -0.05) *
                          Eigen::Isometry3d::Identity());
      EXPECT_NE(world.revision(), before);
    }
    if (k == 500) {
      // A copy has its own revision.
      const CollisionWorld copy = world;
      EXPECT_NE(copy.revision(), world.revision());
    }
    const double cutoff = k < 600 ? kCutoff_m : 0.05;  // the cutoff changes at 600
    SnchGlobalSearch fresh(SnchSearchOptions{1, false});
    fresh.search(world, fk, cutoff, kPruneRadius_m, a);
    coherent.search(world, fk, cutoff, kPruneRadius_m, b);
    expectBitForBit(a, b, "posture " + std::to_string(k));
    if (::testing::Test::HasFatalFailure()) return;
  }
}

TEST(CoherentSearchTest, ThreadsMustBePositive) {
  EXPECT_THROW(SnchGlobalSearch(SnchSearchOptions{0, true}), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::haptics
