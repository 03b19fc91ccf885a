// The Bullet alternative search against SNCH and exact geometry: every SNCH minimum within L
// appears among Bullet's per-triangle closest points (for capsule links, Bullet's capsule against
// each object triangle; for mesh links, the same triangle pair or feature pair), the distances
// Bullet reports are never below the exact ones, the whole Bullet search returns SNCH's minima on
// the valve scene, and GJK/EPA penetration depths equal the analytic depths of a capsule in a box.
#include "fullarm/haptics/bullet_search.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/mesh_import.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/haptics/snch.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

// Bullet's GJK (double precision, zero margins) stops early on triangle pairs: its distances
// come out up to millimetres long (printed by the test; 2.8 mm measured). They are distances
// between points on the two triangles, so never shorter than the exact distance: that is
// checked; the search re-evaluates every reported pair exactly (evaluateTrianglePair).
constexpr double kRounding = 1e-12;
// EPA penetration depth against the analytic value.
constexpr double kEpaDepthTolerance = 1e-6;

// Places the link so that a random vertex of its mesh faces a random vertex of `object` (their
// pseudo-normals opposed, a random turn about them) up to `spread` outside it: near, and for
// these convex links mostly not intersecting.
Eigen::Isometry3d nearPose(const TriMesh& link_mesh, const TriMesh& object, std::mt19937& rng, double spread) {
  std::uniform_int_distribution<int> lv(0, link_mesh.numVertices() - 1);
  std::uniform_int_distribution<int> ov(0, object.numVertices() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  int v = ov(rng);
  while (object.vertexTriangles(v).empty()) v = ov(rng);
  const int w = lv(rng);
  const Eigen::Vector3d n_object = object.featureNormal({FeatureKind::kVertex, v});
  const Eigen::Vector3d n_link = link_mesh.featureNormal({FeatureKind::kVertex, w});
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::AngleAxisd(2 * M_PI * u(rng), n_object).toRotationMatrix() *
               Eigen::Quaterniond::FromTwoVectors(n_link, -n_object).toRotationMatrix();
  const Eigen::Vector3d target = object.vertex(v) + (0.001 + spread * u(rng)) * n_object;
  X.translation() = target - X.linear() * link_mesh.vertex(w);
  return X;
}

// The link capsule `c` placed by a random rotation so that its point nearest the outside of a
// random vertex of `object` lies `0.001 + spread u` from it along the vertex's pseudo-normal.
Eigen::Isometry3d nearCapsulePose(const Capsule& c, const TriMesh& object, std::mt19937& rng, double spread) {
  std::uniform_int_distribution<int> ov(0, object.numVertices() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  int v = ov(rng);
  while (object.vertexTriangles(v).empty()) v = ov(rng);
  const Eigen::Vector3d n = object.featureNormal({FeatureKind::kVertex, v});
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
  // The end of the segment lowest along n, and the capsule's surface point below it.
  const Eigen::Vector3d a = X.linear() * c.a_m;
  const Eigen::Vector3d b = X.linear() * c.b_m;
  const Eigen::Vector3d low = a.dot(n) <= b.dot(n) ? a : b;
  X.translation() = object.vertex(v) + (0.001 + spread * u(rng) + c.radius_m) * n - low;
  return X;
}

struct Fixture {
  const arm::ArmModel& model = arm::test::defaultModel();
  CollisionWorld world{model};
  std::vector<int> links;  // links with geometry
  /// With `faceted`, the capsule links as their 16 x 4 meshes (the mesh-link path).
  explicit Fixture(bool faceted = false) {
    if (faceted) test::facetCapsuleLinks(world, 16, 4);
    world.addObject(
        "wheel", importMesh(arm::test::sourcePath("scenes/meshes/gazebo-drc/drc_practice_wheel_valve/valve_wheel.dae")),
        Eigen::Isometry3d::Identity());
    world.addObject("frame", makeRectangularFrame(0.36, 0.34, 0.03, 0.05, 0.03), Eigen::Isometry3d::Identity());
    world.addObject("box", makeBox({0.4, 0.4, 0.4}, 0.1), Eigen::Isometry3d::Identity());
    world.addObject("wide_frame", makeRectangularFrame(1.2, 1.2, 0.4, 0.05, 0.1), Eigen::Isometry3d::Identity());
    for (int l = 0; l < world.numLinks(); ++l) {
      if (world.hasLinkGeometry(l)) links.push_back(l);
    }
  }
};

TEST(BulletSearchTest, EverySnchCapsuleMinimumIsAmongBulletsTriangles) {
  Fixture f;
  BulletGlobalSearch bullet(f.world);
  std::mt19937 rng(4321);
  constexpr double kCutoff = 0.03;
  SnchQueryScratch scratch;
  int queries_with_minima = 0;
  long minima_checked = 0;
  long triangles_checked = 0;
  double max_gjk_error = 0.0;
  for (int c = 0; c < 200; ++c) {
    const int link = f.links[static_cast<std::size_t>(c) % f.links.size()];
    const int object = (c / 2) % f.world.numObjects();
    const Capsule& capsule = f.world.linkCapsule(link);
    const CollisionObject& obj = f.world.object(object);
    const Eigen::Isometry3d X_WL = nearCapsulePose(capsule, obj.mesh, rng, 0.03);
    std::vector<LocalMinimum> snch;
    querySnchCapsule(capsule, X_WL, obj.tree, obj.mesh, obj.X_WO, kCutoff, scratch, snch);
    std::vector<TrianglePairPoints> pairs;
    bullet.closestTrianglePairs(link, X_WL, object, obj.X_WO, kCutoff, pairs);
    const Eigen::Isometry3d X_OL = obj.X_WO.inverse() * X_WL;
    const Eigen::Vector3d a = X_OL * capsule.a_m;
    const Eigen::Vector3d b = X_OL * capsule.b_m;
    // Bullet's capsule-triangle GJK distances are upper bounds of the exact ones
    // (segment-triangle distance minus the radius), not always tight: the search does not use
    // them to discard triangles.
    for (const TrianglePairPoints& p : pairs) {
      EXPECT_EQ(p.tri_link, -1);
      const auto& t = obj.mesh.triangle(p.tri_object);
      const SegmentTriangleResult exact = closestPointsSegmentTriangle(
          a, b, prepareTriangle(obj.mesh.vertex(t[0]), obj.mesh.vertex(t[1]), obj.mesh.vertex(t[2])));
      const double d = std::max(0.0, std::sqrt(exact.distance_sq) - capsule.radius_m);
      if (p.distance_m >= 0.0) {
        EXPECT_GE(p.distance_m, d - kRounding) << "case " << c;
        max_gjk_error = std::max(max_gjk_error, p.distance_m - d);
      }
      ++triangles_checked;
    }
    // Every SNCH minimum's triangle is among the candidates of Bullet's BVH, and the exact test
    // on the candidates gives exactly SNCH's minima.
    std::vector<int> candidates;
    bullet.capsuleCandidateTriangles(link, X_WL, object, obj.X_WO, kCutoff, candidates);
    std::vector<LocalMinimum> from_bullet;
    LocalMinimum e;
    for (const int t : candidates) {
      if (evaluateCapsuleTriangle(a, b, capsule.radius_m, X_OL.inverse(), obj.mesh, t, kCutoff, e)) {
        from_bullet.push_back(e);
      }
    }
    mergeDuplicateMinima(from_bullet, 0);
    EXPECT_EQ(from_bullet.size(), snch.size()) << "case " << c;
    for (const LocalMinimum& m : snch) {
      EXPECT_TRUE(std::binary_search(candidates.begin(), candidates.end(), m.tri_object))
          << "case " << c << ": SNCH minimum at " << m.distance_m << " m (triangle " << m.tri_object
          << ") missing from Bullet's " << candidates.size() << " candidates";
      EXPECT_TRUE(std::any_of(
          from_bullet.begin(), from_bullet.end(),
          [&](const LocalMinimum& x) { return x.feature_object == m.feature_object && x.distance_m == m.distance_m; }))
          << "case " << c;
      ++minima_checked;
    }
    queries_with_minima += snch.empty() ? 0 : 1;
  }
  EXPECT_GT(queries_with_minima, 150);
  EXPECT_GT(minima_checked, 200);
  EXPECT_GT(triangles_checked, 1000);
  std::cout << "max Bullet GJK - exact = " << max_gjk_error << " m over " << triangles_checked << " triangles\n";
}

TEST(BulletSearchTest, EverySnchMinimumIsAmongBulletsTrianglePairs) {
  Fixture f(true);
  BulletGlobalSearch bullet(f.world);
  std::mt19937 rng(1234);
  constexpr double kCutoff = 0.03;
  SnchQueryScratch scratch;
  int queries_with_minima = 0;
  long minima_checked = 0;
  long pairs_checked = 0;
  double max_gjk_error = 0.0;
  int intersecting = 0;
  for (int c = 0; c < 200; ++c) {
    const int link = f.links[static_cast<std::size_t>(c) % f.links.size()];
    const int object = (c / 2) % f.world.numObjects();
    const TriMesh& link_mesh = f.world.linkMesh(link);
    const CollisionObject& obj = f.world.object(object);
    const Eigen::Isometry3d X_WL = nearPose(link_mesh, obj.mesh, rng, 0.03);
    std::vector<LocalMinimum> snch;
    querySnchPair(f.world.linkTree(link), link_mesh, X_WL, obj.tree, obj.mesh, obj.X_WO, kCutoff, scratch, snch);
    // Intersecting meshes are outside the comparison: Bullet's GJK/EPA on intersecting
    // triangle pairs does not give their (zero) distance.
    if (std::any_of(snch.begin(), snch.end(), [](const LocalMinimum& m) { return m.distance_m == 0.0; })) {
      ++intersecting;
      continue;
    }
    std::vector<TrianglePairPoints> pairs;
    bullet.closestTrianglePairs(link, X_WL, object, obj.X_WO, kCutoff, pairs);
    const Eigen::Isometry3d X_OL = obj.X_WO.inverse() * X_WL;
    // Bullet's distances are upper bounds of the exact triangle-triangle distances.
    for (const TrianglePairPoints& p : pairs) {
      const TriangleTriangleResult exact =
          closestPointsInObjectFrame(link_mesh, p.tri_link, obj.mesh, p.tri_object, X_OL);
      ASSERT_GE(p.distance_m, exact.distance_m - kRounding) << "case " << c;
      ++pairs_checked;
      max_gjk_error = std::max(max_gjk_error, std::abs(p.distance_m - exact.distance_m));
    }
    // Every SNCH minimum: same triangle pair, or a Bullet pair whose exact test gives the same
    // feature pair (adjacent triangles share an edge or vertex minimum).
    for (const LocalMinimum& m : snch) {
      bool found = false;
      for (const TrianglePairPoints& p : pairs) {
        if (p.tri_link == m.tri_link && p.tri_object == m.tri_object) {
          found = true;
          break;
        }
        LocalMinimum e;
        if (evaluateTrianglePair(link_mesh, p.tri_link, obj.mesh, p.tri_object, X_OL, kCutoff, e) &&
            e.feature_link == m.feature_link && e.feature_object == m.feature_object) {
          found = true;
          break;
        }
      }
      EXPECT_TRUE(found) << "case " << c << ": SNCH minimum at " << m.distance_m << " m (triangles " << m.tri_link
                         << "/" << m.tri_object << ") missing from Bullet's " << pairs.size() << " pairs";
      ++minima_checked;
    }
    queries_with_minima += snch.empty() ? 0 : 1;
  }
  // The poses must exercise the comparison.
  EXPECT_GT(queries_with_minima, 100);
  EXPECT_GT(minima_checked, 200);
  EXPECT_GT(pairs_checked, 1000);
  std::cout << "max |Bullet GJK - exact| = " << max_gjk_error << " m over " << pairs_checked << " pairs; "
            << intersecting << " intersecting poses skipped\n";
  EXPECT_LT(intersecting, 80);
}

TEST(BulletSearchTest, BulletSearchReturnsSnchMinimaOnTheValveScene) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  const CollisionWorld world = makeCollisionWorld(scene, model);
  BulletGlobalSearch bullet(world);
  SnchGlobalSearch snch;
  arm::ArmData fk(model);
  std::vector<Eigen::VectorXd> postures = {scenePosture(scene, "reach_valve", model),
                                           scenePosture(scene, "rest", model)};
  // Small perturbations of the reach (still through the opening).
  std::mt19937 rng(99);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  for (int i = 0; i < 3; ++i) {
    Eigen::VectorXd q = postures[0];
    for (int j = 0; j < 7; ++j) q[j] += u(rng);
    postures.push_back(q.cwiseMax(model.lowerLimits()).cwiseMin(model.upperLimits()));
  }
  int total = 0;
  for (const Eigen::VectorXd& q : postures) {
    arm::computeForwardKinematics(model, fk, q);
    std::vector<LocalMinimum> a;
    std::vector<LocalMinimum> b;
    snch.search(world, fk, 0.03, 0.02, a);
    bullet.search(world, fk, 0.03, 0.02, b);
    ASSERT_EQ(a.size(), b.size()) << "posture " << q.transpose();
    for (std::size_t i = 0; i < a.size(); ++i) {
      EXPECT_EQ(a[i].link, b[i].link);
      EXPECT_EQ(a[i].object, b[i].object);
      EXPECT_TRUE(sameFeaturePair(a[i], b[i])) << i;
      EXPECT_NEAR(a[i].distance_m, b[i].distance_m, 1e-12);
      EXPECT_LT((a[i].u_W - b[i].u_W).norm(), 1e-9);
    }
    total += static_cast<int>(a.size());
  }
  EXPECT_GT(total, 5);
}

TEST(BulletSearchTest, EpaDepthOfTheForearmCapsuleInABoxIsAnalytic) {
  Fixture f;
  BulletGlobalSearch bullet(f.world);
  const int forearm = f.model.jointIndex("R_WR");
  const arm::LinkGeometry& g = f.model.joints[static_cast<std::size_t>(forearm)].geometry;
  const double r = g.radius_m;
  const int box = 2;  // 0.4 m cube centred at the origin: top face z = 0.2
  // Link frame placed so that the capsule axis is horizontal (along x) at height h.
  auto lyingAt = [&](double h) {
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();  // link z -> world x
    const Eigen::Vector3d mid = X.linear() * (0.5 * (g.from_m + g.to_m));
    X.translation() = Eigen::Vector3d(0.0, 0.0, h) - mid;
    return X;
  };
  // Apart: no penetration.
  EXPECT_FALSE(bullet.penetration(forearm, lyingAt(0.2 + r + 0.01), box, Eigen::Isometry3d::Identity()).penetrating);
  // Shallow (axis above the face) and deep (axis below it): the box is convex, so the depth is
  // the solid depth r + (0.2 - h) either way.
  for (double h : {0.2 + 0.7 * r, 0.2 + 0.1 * r, 0.2 - 0.5 * r, 0.15}) {
    const LinkPenetration p = bullet.penetration(forearm, lyingAt(h), box, Eigen::Isometry3d::Identity());
    EXPECT_TRUE(p.penetrating) << h;
    EXPECT_TRUE(p.solid_object);
    EXPECT_NEAR(p.depth_m, r + 0.2 - h, kEpaDepthTolerance) << "axis height " << h;
  }
  // A tilted capsule dips one end sphere into the face: depth r - (height of that end centre).
  Eigen::Isometry3d tilted = Eigen::Isometry3d::Identity();
  tilted.linear() = Eigen::AngleAxisd(0.6, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d end_W = tilted.linear() * g.from_m;
  const Eigen::Vector3d other_W = tilted.linear() * g.to_m;
  const Eigen::Vector3d lowest = end_W.z() < other_W.z() ? end_W : other_W;
  tilted.translation() = Eigen::Vector3d(0.05, 0.0, 0.2 + 0.4 * r) - lowest;
  const LinkPenetration p = bullet.penetration(forearm, tilted, box, Eigen::Isometry3d::Identity());
  EXPECT_NEAR(p.depth_m, 0.6 * r, kEpaDepthTolerance);
  EXPECT_NEAR(p.q_W.z(), 0.2, kEpaDepthTolerance);  // the object point lies on the face

  // A non-convex object (a frame with 0.4 m bars) is a surface: shallow penetration of its
  // front face (z = 0.025; the frame lies in x-y, 0.05 m deep) has the solid depth r - h'.
  Eigen::Isometry3d on_bar = lyingAt(0.025 + 0.4 * r);
  on_bar.translation() += Eigen::Vector3d(0.0, 0.4, 0.0);  // over the middle of the top bar
  const LinkPenetration s = bullet.penetration(forearm, on_bar, 3, Eigen::Isometry3d::Identity());
  EXPECT_FALSE(s.solid_object);
  EXPECT_NEAR(s.depth_m, 0.6 * r, kEpaDepthTolerance);
}

}  // namespace
}  // namespace fullarm::haptics
