// Local descent against a fresh global search (SNCH, itself checked against brute force):
// after a random small motion every tracked minimum that is still a local minimum is found
// by the fresh search with the same feature pair and the same distance (1e-9 m). Also:
// merging, iteration bound, allocation freedom.
#include "fullarm/haptics/local_descent.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <optional>

#include "alloc_guard.hpp"
#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

using test::randomPose;
using test::randomSmallMesh;

constexpr double kCutoff_m = 0.05;
constexpr int kLink = 4;  // any link index: the test attaches its own mesh

Eigen::Isometry3d smallMotion(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const Eigen::Vector3d axis = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  Eigen::Isometry3d dX = Eigen::Isometry3d::Identity();
  dX.linear() = Eigen::AngleAxisd(u(rng) * 2.0 * M_PI / 180.0, axis).toRotationMatrix();
  dX.translation() = u(rng) * 0.005 * dir;
  return dX;
}

// A 10 x 10 x 4 cm box of 1 cm triangles whose top face carries +-1.5 mm of random relief:
// every bump is a separate local minimum and steps cross vertex one-rings.
TriMesh roughBox(std::mt19937& rng) {
  const TriMesh box = makeBox({0.1, 0.1, 0.04}, 0.01);
  std::uniform_real_distribution<double> bump(-0.0015, 0.0015);
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < box.numVertices(); ++i) {
    Eigen::Vector3d p = box.vertex(i);
    if (p.z() > 0.0 && std::abs(p.x()) < 0.05 - 1e-9 && std::abs(p.y()) < 0.05 - 1e-9) p.z() += bump(rng);
    v.push_back(p);
  }
  for (int i = 0; i < box.numTriangles(); ++i) t.push_back(box.triangle(i));
  return TriMesh::build("rough box", std::move(v), std::move(t));
}

struct WorldFixture {
  CollisionWorld world;
  arm::ArmData fk;
  explicit WorldFixture(const arm::ArmModel& model) : world(model), fk(model) {
    // Park every link far away; each test places the links it uses.
    for (std::size_t i = 0; i < fk.X_WL.size(); ++i) {
      fk.X_WL[i] = Eigen::Translation3d(100.0 * static_cast<double>(i + 1), 0.0, 0.0) * Eigen::Isometry3d::Identity();
    }
  }
  /// Fresh SNCH minima of kLink against object 0 at the link's current pose, tagged with both
  /// indices (the tracked set local descent starts from).
  std::vector<LocalMinimum> seedMinima() const {
    const CollisionObject& obj = world.object(0);
    std::vector<LocalMinimum> minima;
    SnchQueryScratch scratch;
    querySnchPair(world.linkTree(kLink), world.linkMesh(kLink), fk.X_WL[kLink], obj.tree, obj.mesh, obj.X_WO, kCutoff_m,
                  scratch, minima);
    for (auto& m : minima) {
      m.link = kLink;
      m.object = 0;
    }
    return minima;
  }
};

TEST(LocalDescentTest, TrackedMinimaMatchFreshSearchAfterSmallMotion) {
  const arm::ArmModel& model = arm::test::defaultModel();
  std::mt19937 rng(31);
  int tracked_total = 0;
  int confirmed = 0;
  int moved = 0;
  for (int trial = 0; trial < 300; ++trial) {
    WorldFixture s(model);
    s.world.setLinkMesh(kLink, randomSmallMesh(rng));
    s.world.addObject("obj", randomSmallMesh(rng), randomPose(rng, 0.3));
    const CollisionObject& obj = s.world.object(0);
    // Link placed 0.1-0.35 m from the object centre in a random direction.
    Eigen::Isometry3d X_WL = randomPose(rng, 0.0);
    std::normal_distribution<double> n(0.0, 1.0);
    X_WL.translation() = obj.X_WO.translation() + std::uniform_real_distribution<double>(0.1, 0.35)(rng) *
                                                      Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    s.fk.X_WL[kLink] = X_WL;
    std::vector<LocalMinimum> minima = s.seedMinima();
    if (minima.empty()) continue;
    const std::vector<LocalMinimum> before = minima;
    // Small motion, then descent.
    s.fk.X_WL[kLink] = X_WL * smallMotion(rng);
    const int kept = updateMinimaLocalDescent(s.world, s.fk, minima, LocalDescentParams{});
    minima.resize(static_cast<std::size_t>(kept));
    // Fresh global search at the new pose with a wider cutoff (a minimum may have receded).
    std::vector<LocalMinimum> fresh;
    SnchQueryScratch scratch;
    querySnchPair(s.world.linkTree(kLink), s.world.linkMesh(kLink), s.fk.X_WL[kLink], obj.tree, obj.mesh, obj.X_WO,
                  kCutoff_m + 0.02, scratch, fresh);
    const Eigen::Isometry3d X_OL = obj.X_WO.inverse() * s.fk.X_WL[kLink];
    for (const LocalMinimum& m : minima) {
      ++tracked_total;
      // Distance and points are those of the triangle pair the descent ended on.
      const auto r = closestPointsInObjectFrame(s.world.linkMesh(kLink), m.tri_link, obj.mesh, m.tri_object, X_OL);
      EXPECT_NEAR(m.distance_m, r.distance_m, 1e-15);
      EXPECT_NEAR((s.fk.X_WL[kLink] * m.p_L - obj.X_WO * m.p_O).norm(), m.distance_m, 1e-12);
      LocalMinimum e;
      if (!evaluateTrianglePair(s.world.linkMesh(kLink), m.tri_link, obj.mesh, m.tri_object, X_OL, 1.0, e)) continue;
      ++confirmed;
      const auto it = std::find_if(fresh.begin(), fresh.end(), [&](const LocalMinimum& f) {
        return f.feature_link == m.feature_link && f.feature_object == m.feature_object;
      });
      ASSERT_NE(it, fresh.end()) << "trial " << trial << ": tracked minimum not found by the fresh search";
      EXPECT_NEAR(it->distance_m, m.distance_m, 1e-9);
    }
    for (std::size_t i = 0; i < before.size() && i < minima.size(); ++i) {
      if (before[i].tri_link != minima[i].tri_link || before[i].tri_object != minima[i].tri_object) ++moved;
    }
  }
  EXPECT_GT(tracked_total, 200);
  EXPECT_GT(moved, 20);  // the walk was exercised
  // Nearly every tracked minimum is still a local minimum after a small motion.
  EXPECT_GE(confirmed, static_cast<int>(0.9 * tracked_total));
  RecordProperty("tracked", tracked_total);
  RecordProperty("confirmed", confirmed);
}

// A random link orientation, placed above the rough box's top face (2-4 cm from it) or 0.1-0.35 m
// from the centre of a random small mesh in a random direction.
Eigen::Isometry3d linkPoseNear(const CollisionObject& obj, bool rough, std::mt19937& rng) {
  Eigen::Isometry3d X_WL = randomPose(rng, 0.0);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  if (rough) {
    X_WL.translation() = obj.X_WO * Eigen::Vector3d(0.04 * u(rng), 0.04 * u(rng), 0.05 + 0.01 * u(rng));
  } else {
    X_WL.translation() = obj.X_WO.translation() + std::uniform_real_distribution<double>(0.1, 0.35)(rng) *
                                                      Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  }
  return X_WL;
}

// One trial of a shortcut-against-reference comparison: `link_mesh` on the link and an object (the
// dense box with relief when `rough`, else a random small mesh) at a random pose, the link placed
// near it (linkPoseNear), minima seeded by a fresh search, a random small motion, then the update
// once with `reference_params` and once with the defaults (the shortcuts on). Empty when the
// seed search found no minimum.
struct ShortcutTrial {
  std::vector<LocalMinimum> minima;     // updated with LocalDescentParams{}
  std::vector<LocalMinimum> reference;  // updated with the reference parameters
  int kept = 0;
  int kept_ref = 0;
  LocalDescentStats st;
  LocalDescentStats st_ref;
};

std::optional<ShortcutTrial> runShortcutTrial(const arm::ArmModel& model, TriMesh link_mesh, bool rough,
                                              const LocalDescentParams& reference_params, std::mt19937& rng) {
  WorldFixture s(model);
  s.world.setLinkMesh(kLink, std::move(link_mesh));
  s.world.addObject("obj", rough ? roughBox(rng) : randomSmallMesh(rng), randomPose(rng, 0.3));
  const CollisionObject& obj = s.world.object(0);
  const Eigen::Isometry3d X_WL = linkPoseNear(obj, rough, rng);
  s.fk.X_WL[kLink] = X_WL;
  ShortcutTrial t;
  t.minima = s.seedMinima();
  if (t.minima.empty()) return std::nullopt;
  s.fk.X_WL[kLink] = X_WL * smallMotion(rng);
  t.reference = t.minima;
  t.kept_ref = updateMinimaLocalDescent(s.world, s.fk, t.reference, reference_params, &t.st_ref);
  t.kept = updateMinimaLocalDescent(s.world, s.fk, t.minima, LocalDescentParams{}, &t.st);
  return t;
}

// The re-screening shortcut (LocalDescentParams::rescreen_neighbours) against the reference
// path that evaluates every screened neighbour: the same minima (feature pairs, triangles,
// distances, points) after random small motions, on random meshes and on a dense box with
// random relief (where steps cross vertex one-rings, the case the shortcut targets).
TEST(LocalDescentTest, RescreeningGivesTheSameMinimaAsEvaluatingEveryNeighbour) {
  const arm::ArmModel& model = arm::test::defaultModel();
  std::mt19937 rng(57);
  int compared = 0;
  int ties = 0;
  long skipped = 0;
  long evaluated_reference = 0;
  long evaluated_shortcut = 0;
  LocalDescentParams all;
  all.rescreen_neighbours = false;
  for (int trial = 0; trial < 150; ++trial) {
    TriMesh link_mesh = randomSmallMesh(rng);
    std::optional<ShortcutTrial> t = runShortcutTrial(model, std::move(link_mesh), trial % 2 == 0, all, rng);
    if (!t) continue;
    auto& [minima, reference, kept, kept_ref, st, st_ref] = *t;
    ASSERT_EQ(kept, kept_ref) << "trial " << trial;
    // Compared in order of distance: where the paths part at a tie (below), the merge of
    // duplicates can keep the minima in another order.
    auto byDistance = [](std::vector<LocalMinimum>& v, int count) {
      v.resize(static_cast<std::size_t>(count));
      std::stable_sort(v.begin(), v.end(),
                       [](const LocalMinimum& x, const LocalMinimum& y) { return x.distance_m < y.distance_m; });
    };
    byDistance(minima, kept);
    byDistance(reference, kept_ref);
    bool diverged = false;
    for (int i = 0; i < kept; ++i) {
      const LocalMinimum& a = minima[static_cast<std::size_t>(i)];
      const LocalMinimum& b = reference[static_cast<std::size_t>(i)];
      ++compared;
      EXPECT_NEAR(a.distance_m, b.distance_m, 1e-15) << "trial " << trial << ", minimum " << i;
      if (sameFeaturePair(a, b) && a.tri_link == b.tri_link && a.tri_object == b.tri_object) {
        EXPECT_NEAR((a.p_O - b.p_O).norm(), 0.0, 1e-15);
        continue;
      }
      // A tie: the skipped neighbour reaches the same distance in exact arithmetic, and the
      // reference path took it because its evaluation came out lower by rounding (strict
      // decrease); both are minima at the same distance (checked above).
      ++ties;
      diverged = true;
    }
    // Every skipped evaluation is one the reference path ran; the paths only part at a tie.
    if (!diverged) {
      EXPECT_EQ(st.rescreened, st_ref.evaluated - st.evaluated) << "trial " << trial;
    }
    skipped += st.rescreened;
    evaluated_reference += st_ref.evaluated;
    evaluated_shortcut += st.evaluated;
  }
  EXPECT_GT(compared, 300);
  EXPECT_GT(skipped, 30);  // the shortcut was exercised
  EXPECT_LE(ties, compared / 100);
  RecordProperty("compared", compared);
  RecordProperty("ties", ties);
  RecordProperty("skipped", static_cast<int>(skipped));
  RecordProperty("evaluated_reference", static_cast<int>(evaluated_reference));
  RecordProperty("evaluated_shortcut", static_cast<int>(evaluated_shortcut));
}

// The cone shortcut (LocalDescentParams::cone_screening) against the reference path that
// screens every neighbour triangle: a neighbourhood rejected by a cone is one whose every
// triangle the per-triangle screening rejects, so both paths evaluate the same neighbour pairs
// in the same order and must end on identical minima (bit for bit), on random meshes, on the
// dense box with random relief, and on link capsules.
TEST(LocalDescentTest, ConeScreeningGivesTheSameMinimaAsScreeningEveryNeighbour) {
  const arm::ArmModel& model = arm::test::defaultModel();
  std::mt19937 rng(91);
  int compared = 0;
  long cone_rejected = 0;
  long screened_reference = 0;
  long screened_cones = 0;
  LocalDescentParams every;
  every.cone_screening = false;
  for (int trial = 0; trial < 150; ++trial) {
    TriMesh link_mesh = trial % 3 == 0 ? makeCapsule({0, 0, 0}, {0, 0, 0.2}, 0.04, 16, 4) : randomSmallMesh(rng);
    std::optional<ShortcutTrial> t = runShortcutTrial(model, std::move(link_mesh), trial % 2 == 0, every, rng);
    if (!t) continue;
    const auto& [minima, reference, kept, kept_ref, st, st_ref] = *t;
    ASSERT_EQ(kept, kept_ref) << "trial " << trial;
    EXPECT_EQ(st.evaluated, st_ref.evaluated) << "trial " << trial;
    EXPECT_EQ(st.rescreened, st_ref.rescreened) << "trial " << trial;
    EXPECT_EQ(st.steps, st_ref.steps) << "trial " << trial;
    EXPECT_EQ(st_ref.cone_rejected, 0);
    for (int i = 0; i < kept; ++i) {
      const LocalMinimum& a = minima[static_cast<std::size_t>(i)];
      const LocalMinimum& b = reference[static_cast<std::size_t>(i)];
      ++compared;
      EXPECT_TRUE(sameFeaturePair(a, b) && a.tri_link == b.tri_link && a.tri_object == b.tri_object)
          << "trial " << trial << ", minimum " << i;
      EXPECT_EQ(a.distance_m, b.distance_m) << "trial " << trial << ", minimum " << i;
      EXPECT_EQ(a.p_O, b.p_O);
      EXPECT_EQ(a.p_L, b.p_L);
    }
    cone_rejected += st.cone_rejected;
    screened_reference += st_ref.screened;
    screened_cones += st.screened;
  }
  EXPECT_GT(compared, 300);
  // The shortcut was exercised: it skipped a large share of the per-triangle screenings.
  EXPECT_GT(cone_rejected, 200);
  EXPECT_LT(screened_cones, screened_reference);
  RecordProperty("compared", compared);
  RecordProperty("cone_rejected", static_cast<int>(cone_rejected));
  RecordProperty("screened_reference", static_cast<int>(screened_reference));
  RecordProperty("screened_cones", static_cast<int>(screened_cones));
}

TEST(LocalDescentTest, WalksAcrossAFlatWallAndMergesDuplicates) {
  const arm::ArmModel& model = arm::test::defaultModel();
  WorldFixture s(model);
  // A sphere (zero-length capsule) 5 mm above a densely triangulated wall (z = 0 face).
  s.world.setLinkMesh(kLink, makeCapsule({0, 0, 0}, {0, 0, 0}, 0.03, 16, 8));
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  X_WO.translation() = Eigen::Vector3d(0, 0, -0.01);
  s.world.addObject("wall", makeBox({0.6, 0.6, 0.02}, 0.01), X_WO);
  Eigen::Isometry3d X_WL = Eigen::Isometry3d::Identity();
  X_WL.translation() = Eigen::Vector3d(0.0013, 0.0021, 0.035);
  s.fk.X_WL[kLink] = X_WL;
  std::vector<LocalMinimum> minima;
  globalSearch(s.world, s.fk, 0.02, 0.0, minima);
  ASSERT_FALSE(minima.empty());
  // Slide 0.1 m in 1 mm steps: the sphere's lowest vertex stays 5 mm above the wall.
  LocalDescentStats stats;
  for (int step = 0; step < 100; ++step) {
    X_WL.translation().x() += 0.001;
    s.fk.X_WL[kLink] = X_WL;
    const int kept = updateMinimaLocalDescent(s.world, s.fk, minima, LocalDescentParams{}, &stats);
    minima.resize(static_cast<std::size_t>(kept));
    const double best = std::min_element(minima.begin(), minima.end(), [](auto& a, auto& b) {
                          return a.distance_m < b.distance_m;
                        })->distance_m;
    EXPECT_NEAR(best, 0.005, 1e-12) << "step " << step;
    EXPECT_EQ(stats.minima_at_iteration_cap, 0);
  }
  // Two copies of one minimum converge to the same feature pair and merge.
  std::vector<LocalMinimum> twins{minima.front(), minima.front()};
  const int kept = updateMinimaLocalDescent(s.world, s.fk, twins, LocalDescentParams{}, &stats);
  EXPECT_EQ(kept, 1);
  EXPECT_EQ(stats.merged, 1);
}

TEST(LocalDescentTest, MergesDuplicatesThatAreNotAdjacent) {
  // Minima usually come grouped by link/object pair, but adoptGlobalMinima appends fresh ones
  // after the tracked set: a pair can reappear after another pair's run. Duplicates across such
  // runs must still merge.
  const arm::ArmModel& model = arm::test::defaultModel();
  WorldFixture s(model);
  constexpr int kOther = kLink + 1;
  s.world.setLinkMesh(kLink, makeCapsule({0, 0, 0}, {0, 0, 0}, 0.03, 16, 8));
  s.world.setLinkMesh(kOther, makeCapsule({0, 0, 0}, {0, 0, 0}, 0.03, 16, 8));
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  X_WO.translation() = Eigen::Vector3d(0, 0, -0.01);
  s.world.addObject("wall", makeBox({0.6, 0.6, 0.02}, 0.01), X_WO);
  s.fk.X_WL[kLink] = Eigen::Translation3d(0.0013, 0.0021, 0.035) * Eigen::Isometry3d::Identity();
  s.fk.X_WL[kOther] = Eigen::Translation3d(0.2013, 0.0021, 0.035) * Eigen::Isometry3d::Identity();
  std::vector<LocalMinimum> found;
  globalSearch(s.world, s.fk, 0.02, 0.0, found);
  const auto a = std::find_if(found.begin(), found.end(), [](const LocalMinimum& m) { return m.link == kLink; });
  const auto b = std::find_if(found.begin(), found.end(), [](const LocalMinimum& m) { return m.link == kOther; });
  ASSERT_NE(a, found.end());
  ASSERT_NE(b, found.end());
  std::vector<LocalMinimum> minima{*a, *b, *a, *b, *a};
  LocalDescentStats stats;
  const int kept = updateMinimaLocalDescent(s.world, s.fk, minima, LocalDescentParams{}, &stats);
  EXPECT_EQ(kept, 2);
  EXPECT_EQ(stats.merged, 3);
  EXPECT_EQ(minima[0].link, kLink);
  EXPECT_EQ(minima[1].link, kOther);
}

TEST(LocalDescentTest, IterationCapBoundsTheWalk) {
  const arm::ArmModel& model = arm::test::defaultModel();
  WorldFixture s(model);
  s.world.setLinkMesh(kLink, makeCapsule({0, 0, 0}, {0, 0, 0}, 0.03, 16, 8));
  s.world.addObject("wall", makeBox({0.6, 0.6, 0.02}, 0.005), Eigen::Isometry3d::Identity());
  Eigen::Isometry3d X_WL = Eigen::Isometry3d::Identity();
  X_WL.translation() = Eigen::Vector3d(0, 0, 0.045);
  s.fk.X_WL[kLink] = X_WL;
  std::vector<LocalMinimum> minima;
  globalSearch(s.world, s.fk, 0.02, 0.0, minima);
  ASSERT_FALSE(minima.empty());
  // Jump 10 cm sideways: the walk over 5 mm triangles needs more than 2 steps.
  X_WL.translation().x() += 0.1;
  s.fk.X_WL[kLink] = X_WL;
  LocalDescentParams p;
  p.max_iterations = 2;
  LocalDescentStats stats;
  (void)updateMinimaLocalDescent(s.world, s.fk, minima, p, &stats);
  EXPECT_GT(stats.minima_at_iteration_cap, 0);
  EXPECT_LE(stats.steps, 2 * static_cast<int>(minima.size()));
}

// The allocation test on the world's links as exact capsules and as faceted meshes.
void expectUpdateDoesNotAllocate(bool faceted) {
  const arm::ArmModel& model = arm::test::defaultModel();
  WorldFixture s(model);
  if (faceted) test::facetCapsuleLinks(s.world, 16, 4);
  s.world.addObject("beam", makeIBeam(0.2, 0.1, 0.02, 0.01, 1.0, 0.02), Eigen::Isometry3d::Identity());
  arm::computeForwardKinematics(model, s.fk, model.defaultPosture());
  // Put every link mesh near the beam by moving the beam next to the forearm.
  const Eigen::Vector3d p = s.fk.X_WL[4].translation();
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  X_WO.translation() = p + Eigen::Vector3d(0.0, 0.0, -0.12);
  s.world.setObjectPose(0, X_WO);
  std::vector<LocalMinimum> minima;
  globalSearch(s.world, s.fk, 0.2, 0.0, minima);
  ASSERT_FALSE(minima.empty());
  Eigen::VectorXd q = model.defaultPosture();
  q[0] += 0.01;
  arm::computeForwardKinematics(model, s.fk, q);
  LocalDescentStats stats;
  int kept = 0;
  EXPECT_NO_HEAP_ALLOCATION(kept = updateMinimaLocalDescent(s.world, s.fk, minima, LocalDescentParams{}, &stats));
  EXPECT_GT(kept, 0);
}

TEST(LocalDescentTest, UpdateDoesNotAllocate) {
  expectUpdateDoesNotAllocate(false);
}

TEST(LocalDescentTest, UpdateOfMeshLinksDoesNotAllocate) {
  expectUpdateDoesNotAllocate(true);
}

// ---------------------------------------------------------------------------------------------
// Exact capsule links.

// Fresh capsule minima of kLink (the model's forearm capsule) against object 0, tagged.
std::vector<LocalMinimum> seedCapsuleMinima(const WorldFixture& s, double cutoff_m) {
  const CollisionObject& obj = s.world.object(0);
  std::vector<LocalMinimum> minima;
  SnchQueryScratch scratch;
  querySnchCapsule(s.world.linkCapsule(kLink), s.fk.X_WL[kLink], obj.tree, obj.mesh, obj.X_WO, cutoff_m, scratch,
                   minima);
  for (auto& m : minima) {
    m.link = kLink;
    m.object = 0;
  }
  return minima;
}

// The exact capsule under motion: 150 random objects (random primitives and the relief box),
// the capsule 2-6 cm from them, then 12 small random motions in a row, local descent after each.
// After every motion, each tracked minimum that is still a local minimum at its triangle (the
// exact test) is found by a fresh global search with the same feature pair and bit for bit the
// same distance and points (both fill a capsule minimum from its feature alone), and the
// reference path of the descent (no rejection cones, no re-screening) gives the same minima bit
// for bit.
TEST(LocalDescentTest, CapsuleMinimaStayExactUnderMotion) {
  const arm::ArmModel& model = arm::test::defaultModel();
  std::mt19937 rng(41);
  int tracked_total = 0;
  int confirmed = 0;
  int steps = 0;
  int skipped = 0;  // neighbours or neighbourhoods skipped by re-screening or a rejection cone
  for (int trial = 0; trial < 150; ++trial) {
    WorldFixture s(model);
    ASSERT_EQ(s.world.linkShape(kLink), LinkShape::kCapsule);
    const Capsule& c = s.world.linkCapsule(kLink);
    s.world.addObject("obj", trial % 3 == 0 ? randomSmallMesh(rng) : roughBox(rng), randomPose(rng, 0.3));
    const CollisionObject& obj = s.world.object(0);
    // The capsule's middle 2-6 cm + radius + object size from the object's centre.
    Eigen::Isometry3d X_WL = randomPose(rng, 0.0);
    std::normal_distribution<double> n(0.0, 1.0);
    const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
    X_WL.translation() = obj.X_WO.translation() +
                         (std::uniform_real_distribution<double>(0.08, 0.2)(rng) + c.radius_m) * dir -
                         X_WL.linear() * (0.5 * (c.a_m + c.b_m));
    s.fk.X_WL[kLink] = X_WL;
    std::vector<LocalMinimum> minima = seedCapsuleMinima(s, kCutoff_m);
    if (minima.empty()) continue;
    // The reference path (every neighbour screened one by one, none skipped by re-screening)
    // on a copy: the same minima bit for bit.
    std::vector<LocalMinimum> reference = minima;
    LocalDescentParams reference_params;
    reference_params.rescreen_neighbours = false;
    reference_params.cone_screening = false;
    for (int motion = 0; motion < 12; ++motion) {
      s.fk.X_WL[kLink] = s.fk.X_WL[kLink] * smallMotion(rng);
      LocalDescentStats stats;
      const int kept = updateMinimaLocalDescent(s.world, s.fk, minima, LocalDescentParams{}, &stats);
      minima.resize(static_cast<std::size_t>(kept));
      steps += stats.steps;
      skipped += stats.rescreened + stats.cone_rejected;
      const int kept_reference = updateMinimaLocalDescent(s.world, s.fk, reference, reference_params);
      reference.resize(static_cast<std::size_t>(kept_reference));
      ASSERT_EQ(reference.size(), minima.size());
      for (std::size_t i = 0; i < minima.size(); ++i) {
        EXPECT_TRUE(sameFeaturePair(reference[i], minima[i]));
        EXPECT_EQ(reference[i].distance_m, minima[i].distance_m);
        EXPECT_EQ(reference[i].p_L, minima[i].p_L);
      }
      const std::vector<LocalMinimum> fresh = seedCapsuleMinima(s, kCutoff_m + 0.05);
      const Eigen::Isometry3d X_OL = obj.X_WO.inverse() * s.fk.X_WL[kLink];
      for (const LocalMinimum& m : minima) {
        ++tracked_total;
        EXPECT_EQ(m.tri_link, -1);
        LocalMinimum e;
        if (!evaluateCapsuleTriangle(X_OL * c.a_m, X_OL * c.b_m, c.radius_m, X_OL.inverse(), obj.mesh, m.tri_object,
                                     1.0, e) ||
            e.feature_object != m.feature_object) {
          continue;
        }
        ++confirmed;
        const auto it =
            std::find_if(fresh.begin(), fresh.end(), [&](const LocalMinimum& f) { return sameFeaturePair(f, m); });
        ASSERT_NE(it, fresh.end()) << "trial " << trial << ", motion " << motion;
        EXPECT_EQ(it->distance_m, m.distance_m);
        EXPECT_EQ(it->p_L, m.p_L);
        EXPECT_EQ(it->p_O, m.p_O);
        EXPECT_LT((it->u_W - m.u_W).norm(), 1e-15);
        // The link point lies on the capsule (within it when the segment itself meets the
        // object), the distance apart from the object point.
        const double s_param = closestSegmentParameter(c.a_m, c.b_m, m.p_L);
        const double from_axis = (m.p_L - (c.a_m + s_param * (c.b_m - c.a_m))).norm();
        if (m.distance_m > 0.0) {
          EXPECT_NEAR(from_axis, c.radius_m, 1e-12);
          EXPECT_NEAR((s.fk.X_WL[kLink] * m.p_L - obj.X_WO * m.p_O).norm(), m.distance_m, 1e-12);
        } else {
          EXPECT_LE(from_axis, c.radius_m + 1e-12);
        }
      }
    }
  }
  std::cout << tracked_total << " tracked minima, " << confirmed << " confirmed, " << steps << " walk steps, "
            << skipped << " neighbours or neighbourhoods skipped\n";
  EXPECT_GT(tracked_total, 1000);
  EXPECT_GT(steps, 100);  // the walk was exercised (203 steps)
  EXPECT_GT(skipped, 500);  // 887
  EXPECT_GE(confirmed, static_cast<int>(0.9 * tracked_total));
  RecordProperty("tracked", tracked_total);
  RecordProperty("confirmed", confirmed);
}

// A tilted capsule (the forearm's) sliding 10 cm over a wall of 1 cm triangles: its lower end
// cap stays 5 mm above the wall, and descent keeps exactly that distance while it walks.
TEST(LocalDescentTest, CapsuleWalksAcrossAFlatWall) {
  const arm::ArmModel& model = arm::test::defaultModel();
  WorldFixture s(model);
  const Capsule& c = s.world.linkCapsule(kLink);
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  X_WO.translation() = Eigen::Vector3d(0, 0, -0.01);  // top face at z = 0
  s.world.addObject("wall", makeBox({0.6, 0.6, 0.02}, 0.01), X_WO);
  Eigen::Isometry3d X_WL = Eigen::Isometry3d::Identity();
  X_WL.linear() = Eigen::AngleAxisd(0.5, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d a = X_WL.linear() * c.a_m;
  const Eigen::Vector3d b = X_WL.linear() * c.b_m;
  const Eigen::Vector3d low = a.z() < b.z() ? a : b;
  X_WL.translation() = Eigen::Vector3d(0.0013, 0.0021, 0.005 + c.radius_m) - low;
  s.fk.X_WL[kLink] = X_WL;
  std::vector<LocalMinimum> minima;
  globalSearch(s.world, s.fk, 0.02, 0.0, minima);
  ASSERT_EQ(minima.size(), 1U);
  LocalDescentStats stats;
  int walked = 0;
  for (int step = 0; step < 100; ++step) {
    X_WL.translation().x() += 0.001;
    s.fk.X_WL[kLink] = X_WL;
    const int before = minima[0].tri_object;
    const int kept = updateMinimaLocalDescent(s.world, s.fk, minima, LocalDescentParams{}, &stats);
    ASSERT_EQ(kept, 1);
    EXPECT_NEAR(minima[0].distance_m, 0.005, 1e-15) << "step " << step;
    EXPECT_NEAR(minima[0].u_W.z(), -1.0, 1e-15);
    EXPECT_EQ(stats.minima_at_iteration_cap, 0);
    walked += minima[0].tri_object != before ? 1 : 0;
  }
  EXPECT_GT(walked, 10);
}

}  // namespace
}  // namespace fullarm::haptics
