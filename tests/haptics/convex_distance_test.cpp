// The convex-link path of the SNCH query against independent oracles:
// - convexSupportVertex (hill climbing on the vertex graph) against the maximum over all
//   vertices (brute force);
// - triangleConvexMeshDistanceBounds (GJK) against brute force: the distance between a
//   triangle and a closed convex mesh's body is 0 when the triangle touches the body, else the
//   smallest triangle-triangle distance over the mesh's triangles; the bounds must bracket it,
//   converge to the tolerance, and the returned axis must separate the triangle from every
//   mesh vertex by the lower bound;
// - SnchTree::convex against the definition (capsules, boxes, cylinders yes; I-beams, frames,
//   a dented capsule, an open sheet no);
// - querySnchPair with a convex link: exactly the brute-force minima and the same minima as the
//   same query with the convex-link bound switched off (a copy of the tree with convex =
//   false), with fewer exact tests; this is the test that fails when the bound is made too
//   tight (checked by mutation: limit = bound - 0.1 mm, and the GJK axis negated);
// - the bracket capsules (buildConvexBracket) and their point and triangle distance bounds
//   against brute force and a golden-section search along the segment; the support table's
//   start vertices against the brute-force maximum.
#include "fullarm/haptics/convex_distance.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include "alloc_guard.hpp"
#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/snch.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

using Eigen::Vector3d;

Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vector3d(n(rng), n(rng), n(rng)).normalized();
}

// A random triangle 1-60 mm across (written to t) around a random centre (returned) that lies
// from inside the random convex bodies of these tests to 0.1 m outside them.
Vector3d randomTriangleNearBody(std::mt19937& rng, Vector3d (&t)[3]) {
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  const Vector3d centre = Vector3d(u(rng), u(rng), u(rng) + 0.1);
  const double size = std::uniform_real_distribution<double>(0.001, 0.06)(rng);
  for (Vector3d& corner : t) corner = centre + size * randomUnit(rng);
  return centre;
}

// A random closed convex mesh: capsule, box or cylinder, 0.05-0.3 m.
TriMesh randomConvexMesh(std::mt19937& rng) {
  std::uniform_real_distribution<double> size(0.05, 0.3);
  switch (std::uniform_int_distribution<int>(0, 2)(rng)) {
    case 0:
      return makeCapsule({0, 0, 0}, {0, 0, size(rng)}, 0.2 * size(rng), std::uniform_int_distribution<int>(5, 16)(rng),
                         std::uniform_int_distribution<int>(1, 4)(rng));
    case 1:
      return makeBox({size(rng), size(rng), size(rng)}, std::uniform_real_distribution<double>(0.03, 0.3)(rng));
    default:
      return makeCylinder(0.5 * size(rng), size(rng), std::uniform_int_distribution<int>(5, 16)(rng), 0.1);
  }
}

std::vector<Vector3d> verticesOf(const TriMesh& m) {
  std::vector<Vector3d> v;
  for (int i = 0; i < m.numVertices(); ++i) v.push_back(m.vertex(i));
  return v;
}

// Whether p is inside the closed convex mesh: behind (or on) every face plane.
bool insideConvexMesh(const Vector3d& p, const TriMesh& m) {
  for (int f = 0; f < m.numTriangles(); ++f) {
    if (!(m.faceNormal(f).dot(p - m.vertex(m.triangle(f)[0])) <= 0.0)) return false;
  }
  return true;
}

// Brute force: 0 if a triangle vertex is inside the closed convex mesh or the triangle meets a
// mesh triangle; else the smallest triangle-triangle distance.
double bruteForceDistance(const Vector3d (&t)[3], const TriMesh& m) {
  for (const Vector3d& p : t) {
    if (insideConvexMesh(p, m)) return 0.0;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int f = 0; f < m.numTriangles(); ++f) {
    const auto& tri = m.triangle(f);
    best = std::min(
        best, closestPointsTriangleTriangle(t[0], t[1], t[2], m.vertex(tri[0]), m.vertex(tri[1]), m.vertex(tri[2]))
                  .distance_m);
  }
  return best;
}

TEST(ConvexDistanceTest, SupportVertexIsTheFarthestVertex) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 300; ++trial) {
    const TriMesh m = randomConvexMesh(rng);
    const std::vector<Vector3d> v = verticesOf(m);
    const VertexGraph graph = buildVertexGraph(m);
    for (int k = 0; k < 10; ++k) {
      const Vector3d d = randomUnit(rng);
      const int start = std::uniform_int_distribution<int>(0, m.numVertices() - 1)(rng);
      const int s = convexSupportVertex(graph, v, d, start);
      double best = -std::numeric_limits<double>::infinity();
      for (const Vector3d& p : v) best = std::max(best, p.dot(d));
      EXPECT_EQ(v[static_cast<std::size_t>(s)].dot(d), best) << "trial " << trial;
    }
  }
}

TEST(ConvexDistanceTest, TriangleBoundsBracketTheBruteForceDistance) {
  std::mt19937 rng(12);
  constexpr double kTolerance_m = 1e-6;
  int touching = 0;
  int apart = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const TriMesh m = randomConvexMesh(rng);
    const std::vector<Vector3d> v = verticesOf(m);
    const VertexGraph graph = buildVertexGraph(m);
    // A random triangle 1-60 mm across around a point from inside the body to 0.1 m outside.
    Vector3d t[3];
    (void)randomTriangleNearBody(rng, t);
    const double brute = bruteForceDistance(t, m);
    int warm = std::uniform_int_distribution<int>(0, m.numVertices() - 1)(rng);
    const DistanceBounds b = triangleConvexMeshDistanceBounds(
        t[0], t[1], t[2], graph, v, std::numeric_limits<double>::infinity(), kTolerance_m, warm);
    EXPECT_LE(b.lower_m, brute + 1e-12) << "trial " << trial;
    EXPECT_GE(b.upper_m, brute - 1e-12) << "trial " << trial;
    EXPECT_LE(b.upper_m - b.lower_m, kTolerance_m + 1e-12) << "trial " << trial;
    if (b.lower_m > 0.0) {
      for (const Vector3d& p : t) {
        for (const Vector3d& q : v) EXPECT_GE(b.axis.dot(p - q), b.lower_m - 1e-12) << "trial " << trial;
      }
    }
    (brute == 0.0 ? touching : apart) += 1;
    // The early stop: a lower bound above the threshold, or bounds already within tolerance.
    int warm2 = 0;
    const DistanceBounds s =
        triangleConvexMeshDistanceBounds(t[0], t[1], t[2], graph, v, 0.5 * brute, kTolerance_m, warm2);
    EXPECT_LE(s.lower_m, brute + 1e-12);
    EXPECT_GE(s.upper_m, brute - 1e-12);
  }
  EXPECT_GT(touching, 20);
  EXPECT_GT(apart, 200);
}

TEST(ConvexDistanceTest, ConvexFlagFollowsTheDefinition) {
  EXPECT_TRUE(buildSnchTree(makeCapsule({0, 0, 0}, {0, 0, 0.3}, 0.05, 16, 4)).convex);
  EXPECT_TRUE(buildSnchTree(makeBox({0.1, 0.2, 0.3}, 0.04)).convex);
  EXPECT_TRUE(buildSnchTree(makeCylinder(0.05, 0.2, 12, 0.05)).convex);
  EXPECT_FALSE(buildSnchTree(makeIBeam(0.12, 0.08, 0.015, 0.01, 0.2, 0.1)).convex);
  EXPECT_FALSE(buildSnchTree(makeRectangularFrame(0.2, 0.16, 0.04, 0.03, 0.08)).convex);
  // A capsule with one vertex of a hemisphere ring pushed 2 mm towards the sphere's centre: a dent.
  const TriMesh capsule = makeCapsule({0, 0, 0}, {0, 0, 0.3}, 0.05, 16, 4);
  std::vector<Vector3d> v = verticesOf(capsule);
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < capsule.numTriangles(); ++i) t.push_back(capsule.triangle(i));
  int ring = -1;
  for (int i = 0; i < capsule.numVertices() && ring < 0; ++i) {
    if (v[static_cast<std::size_t>(i)].z() > 0.31 && v[static_cast<std::size_t>(i)].z() < 0.34) ring = i;
  }
  ASSERT_GE(ring, 0);
  Vector3d& p = v[static_cast<std::size_t>(ring)];
  p -= 0.002 * (p - Vector3d(0, 0, 0.3)).normalized();
  EXPECT_FALSE(buildSnchTree(TriMesh::build("dented capsule", v, t)).convex);
  // An open sheet (one panel of a fold grid) is not a closed surface.
  test::FoldGrid g = test::foldGrid(std::numbers::pi, 3, false);
  EXPECT_FALSE(buildSnchTree(TriMesh::build("sheet", std::move(g.vertices), std::move(g.triangles), 1e-9)).convex);
}

// Random convex links near random objects: the query keeps exactly the brute-force minima with
// the bracket capsules (the default), with the GJK fallback of a link whose bracket is invalid,
// and with the convex pruning off; the convex bounds prune and save exact tests.
TEST(ConvexDistanceTest, ConvexLinkQueryKeepsEveryBruteForceMinimumWithFewerExactTests) {
  std::mt19937 rng(13);
  constexpr double kCutoff_m = 0.05;
  SnchQueryScratch scratch;
  long tests_with = 0;
  long tests_without = 0;
  long pruned = 0;
  long pruned_gjk = 0;
  int cases_with_minima = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const TriMesh link = randomConvexMesh(rng);
    const TriMesh obj = test::randomSmallMesh(rng);
    const SnchTree link_tree = buildSnchTree(link);
    ASSERT_TRUE(link_tree.convex);
    ASSERT_TRUE(link_tree.bracket.valid());
    SnchTree plain_tree = link_tree;
    plain_tree.convex = false;
    // Convex but without a bracket: the query falls back to GJK bounds for object nodes and leaves.
    SnchTree gjk_tree = link_tree;
    gjk_tree.bracket.inner_radius_m = 0.0;
    const SnchTree obj_tree = buildSnchTree(obj);
    // The link placed 0-0.1 m from the object's surface region: many contacts within L.
    const Eigen::Isometry3d X_WO = test::randomPose(rng, 0.5);
    Eigen::Isometry3d X_WL = test::randomPose(rng, 0.0);
    X_WL.translation() = X_WO.translation() + std::uniform_real_distribution<double>(0.05, 0.3)(rng) * randomUnit(rng);
    std::vector<LocalMinimum> with;
    std::vector<LocalMinimum> without;
    SnchQueryStats s_with;
    SnchQueryStats s_without;
    querySnchPair(link_tree, link, X_WL, obj_tree, obj, X_WO, kCutoff_m, scratch, with, &s_with);
    querySnchPair(plain_tree, link, X_WL, obj_tree, obj, X_WO, kCutoff_m, scratch, without, &s_without);
    const std::vector<LocalMinimum> brute = test::bruteForceMinima(link, X_WL, obj, X_WO, kCutoff_m);
    ASSERT_EQ(with.size(), brute.size()) << "trial " << trial;
    ASSERT_EQ(without.size(), brute.size()) << "trial " << trial;
    std::vector<LocalMinimum> with_gjk;
    SnchQueryStats s_gjk;
    querySnchPair(gjk_tree, link, X_WL, obj_tree, obj, X_WO, kCutoff_m, scratch, with_gjk, &s_gjk);
    ASSERT_EQ(with_gjk.size(), brute.size()) << "trial " << trial;
    pruned_gjk += s_gjk.pruned_by_convex_bound;
    for (std::size_t i = 0; i < with.size(); ++i) {
      EXPECT_TRUE(sameFeaturePair(with_gjk[i], brute[i])) << "trial " << trial;
      EXPECT_NEAR(with_gjk[i].distance_m, brute[i].distance_m, 1e-12);
      EXPECT_TRUE(sameFeaturePair(with[i], brute[i])) << "trial " << trial;
      EXPECT_EQ(with[i].tri_link, without[i].tri_link) << "trial " << trial;
      EXPECT_EQ(with[i].tri_object, without[i].tri_object) << "trial " << trial;
      EXPECT_NEAR(with[i].distance_m, brute[i].distance_m, 1e-12);
      EXPECT_NEAR((with[i].u_W - brute[i].u_W).norm(), 0.0, 1e-9);
    }
    tests_with += s_with.triangle_pairs_tested;
    tests_without += s_without.triangle_pairs_tested;
    pruned += s_with.pruned_by_convex_bound;
    EXPECT_EQ(s_without.pruned_by_convex_bound, 0);
    if (!with.empty()) ++cases_with_minima;
  }
  EXPECT_GT(cases_with_minima, 100);
  EXPECT_GT(pruned, 0);
  EXPECT_GT(pruned_gjk, 0);
  EXPECT_LT(tests_with, tests_without);
  RecordProperty("exact_tests_convex", static_cast<int>(tests_with));
  RecordProperty("exact_tests_plain", static_cast<int>(tests_without));
}

// A capsule hovering 2-25 mm over the top face of a densely triangulated box (1 cm grid), at
// random tilts: many object nodes small enough (2 r < D) for the node-direction cone test, and
// minima under the capsule that it must keep. Brute force over all triangle pairs decides.
TEST(ConvexDistanceTest, CapsuleOverADenseFaceKeepsEveryBruteForceMinimum) {
  std::mt19937 rng(14);
  constexpr double kCutoff_m = 0.03;
  const TriMesh box = makeBox({0.12, 0.12, 0.06}, 0.01);  // top face at z = 0.03
  const SnchTree box_tree = buildSnchTree(box);
  const TriMesh capsule = makeCapsule({-0.04, 0, 0}, {0.04, 0, 0}, 0.015, 8, 2);
  const SnchTree capsule_tree = buildSnchTree(capsule);
  ASSERT_TRUE(capsule_tree.convex);
  SnchQueryScratch scratch;
  int minima = 0;
  long pruned_by_cone = 0;
  for (int trial = 0; trial < 30; ++trial) {
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Isometry3d X_WL = Eigen::Isometry3d::Identity();
    X_WL.linear() =
        (Eigen::AngleAxisd(0.4 * u(rng), Vector3d::UnitX()) * Eigen::AngleAxisd(0.4 * u(rng), Vector3d::UnitY()) *
         Eigen::AngleAxisd(3.2 * u(rng), Vector3d::UnitZ()))
            .toRotationMatrix();
    X_WL.translation() = Vector3d(0.03 * u(rng), 0.03 * u(rng), 0.03 + 0.015 + 0.0135 + 0.0115 * u(rng));
    std::vector<LocalMinimum> snch;
    SnchQueryStats stats;
    querySnchPair(capsule_tree, capsule, X_WL, box_tree, box, Eigen::Isometry3d::Identity(), kCutoff_m, scratch, snch,
                  &stats);
    const std::vector<LocalMinimum> brute =
        test::bruteForceMinima(capsule, X_WL, box, Eigen::Isometry3d::Identity(), kCutoff_m);
    ASSERT_EQ(snch.size(), brute.size()) << "trial " << trial;
    for (std::size_t i = 0; i < snch.size(); ++i) {
      EXPECT_TRUE(sameFeaturePair(snch[i], brute[i])) << "trial " << trial;
      EXPECT_NEAR(snch[i].distance_m, brute[i].distance_m, 1e-12);
    }
    minima += static_cast<int>(snch.size());
    pruned_by_cone += stats.pruned_by_cone;
  }
  EXPECT_GT(minima, 30);
  EXPECT_GT(pruned_by_cone, 0);
}

// A convex link mesh whose vertex 0 no triangle uses (as welding or a dropped degenerate
// triangle leaves behind), placed at the body's centre: it is still convex, and the support
// climbs must not start from that isolated vertex (they would never move, GJK would bound the
// distance to one point, and minima would be pruned). Brute force decides.
TEST(ConvexDistanceTest, ConvexLinkWithAnUnusedVertexZeroKeepsEveryBruteForceMinimum) {
  std::mt19937 rng(15);
  constexpr double kCutoff_m = 0.05;
  SnchQueryScratch scratch;
  int minima = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const TriMesh base = randomConvexMesh(rng);
    Vector3d centre = Vector3d::Zero();
    std::vector<Vector3d> vertices{Vector3d::Zero()};
    for (int v = 0; v < base.numVertices(); ++v) {
      vertices.push_back(base.vertex(v));
      centre += base.vertex(v) / base.numVertices();
    }
    vertices[0] = centre;
    std::vector<Eigen::Vector3i> triangles;
    for (int t = 0; t < base.numTriangles(); ++t) triangles.push_back(base.triangle(t) + Eigen::Vector3i::Ones());
    const TriMesh link = TriMesh::build("capsule with an unused vertex 0", vertices, triangles);
    ASSERT_EQ(link.numVertices(), base.numVertices() + 1);
    const SnchTree link_tree = buildSnchTree(link);
    ASSERT_TRUE(link_tree.convex);
    const TriMesh obj = test::randomSmallMesh(rng);
    const SnchTree obj_tree = buildSnchTree(obj);
    const Eigen::Isometry3d X_WO = test::randomPose(rng, 0.5);
    Eigen::Isometry3d X_WL = test::randomPose(rng, 0.0);
    X_WL.translation() = X_WO.translation() + std::uniform_real_distribution<double>(0.05, 0.3)(rng) * randomUnit(rng);
    std::vector<LocalMinimum> snch;
    querySnchPair(link_tree, link, X_WL, obj_tree, obj, X_WO, kCutoff_m, scratch, snch);
    const std::vector<LocalMinimum> brute = test::bruteForceMinima(link, X_WL, obj, X_WO, kCutoff_m);
    ASSERT_EQ(snch.size(), brute.size()) << "trial " << trial;
    for (std::size_t i = 0; i < snch.size(); ++i) {
      EXPECT_TRUE(sameFeaturePair(snch[i], brute[i])) << "trial " << trial;
      EXPECT_NEAR(snch[i].distance_m, brute[i].distance_m, 1e-12);
    }
    minima += static_cast<int>(snch.size());
  }
  EXPECT_GT(minima, 30);
}

// Brute force: distance from a point to the body of a closed convex mesh (0 inside; else the
// nearest triangle).
double bruteForcePointDistance(const Vector3d& p, const TriMesh& m) {
  if (insideConvexMesh(p, m)) return 0.0;
  double best = std::numeric_limits<double>::infinity();
  for (int f = 0; f < m.numTriangles(); ++f) {
    const auto& tri = m.triangle(f);
    best = std::min(best, closestPointTriangle(p, m.vertex(tri[0]), m.vertex(tri[1]), m.vertex(tri[2])).distance_m);
  }
  return best;
}

// Independent oracle of the segment-triangle distance: the distance from the segment's point
// at parameter s to the triangle is convex in s; golden-section search on it.
double segmentTriangleDistanceBySearch(const Vector3d& a, const Vector3d& b, const Vector3d (&t)[3]) {
  const auto f = [&](double s) { return closestPointTriangle(a + s * (b - a), t[0], t[1], t[2]).distance_m; };
  double lo = 0.0;
  double hi = 1.0;
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 200; ++it) {
    const double x1 = hi - g * (hi - lo);
    const double x2 = lo + g * (hi - lo);
    if (f(x1) < f(x2)) {
      hi = x2;
    } else {
      lo = x1;
    }
  }
  return std::min({f(0.0), f(1.0), f(0.5 * (lo + hi))});
}

// The bracket: every vertex within the outer capsule (brute force over the vertices), the inner
// capsule inside the body (its segment's points sampled along with sphere directions: each
// point at the inner radius is behind every face plane), and on the arm's 16 x 4 capsules the
// radii within 4 % of the capsule's (the principal-axis segment found the capsule's axis).
TEST(ConvexDistanceTest, BracketCapsulesHoldTheBodyBetweenThem) {
  std::mt19937 rng(21);
  for (int trial = 0; trial < 200; ++trial) {
    const TriMesh m = randomConvexMesh(rng);
    const ConvexBracket br = buildConvexBracket(m);
    ASSERT_TRUE(br.valid()) << "trial " << trial;
    ASSERT_GE(br.outer_radius_m, br.inner_radius_m);
    for (int v = 0; v < m.numVertices(); ++v) {
      const SegmentSegmentResult r = closestPointsSegmentSegment(m.vertex(v), m.vertex(v), br.a_m, br.b_m);
      EXPECT_LE(r.distance_m, br.outer_radius_m) << "trial " << trial;
    }
    for (int k = 0; k < 40; ++k) {
      const double s = std::uniform_real_distribution<double>(0.0, 1.0)(rng);
      const Vector3d p = br.a_m + s * (br.b_m - br.a_m) + br.inner_radius_m * randomUnit(rng);
      EXPECT_EQ(bruteForcePointDistance(p, m), 0.0) << "trial " << trial;
    }
  }
  const double radius = 0.045;
  const TriMesh capsule = makeCapsule({0.01, 0.02, 0.0}, {0.05, -0.1, 0.25}, radius, 16, 4);
  const ConvexBracket br = buildConvexBracket(capsule);
  EXPECT_NEAR(br.outer_radius_m, radius, 1e-9);
  EXPECT_GT(br.inner_radius_m, 0.96 * radius);
  const Vector3d from(0.01, 0.02, 0.0);
  const Vector3d to(0.05, -0.1, 0.25);
  // The capsule's own axis segment, in either direction.
  EXPECT_LT(std::min((br.a_m - from).norm() + (br.b_m - to).norm(), (br.a_m - to).norm() + (br.b_m - from).norm()),
            1e-9);
}

// The bracket's distance bounds against brute force, for points and for triangles (1-60 mm
// across, from inside the body to 0.1 m out): lower <= distance <= upper, the axis separates
// the point or triangle from every mesh vertex by the lower bound, and the triangle's closest
// pair with the segment is exact (golden-section search along the segment, 1e-9 m).
TEST(ConvexDistanceTest, BracketBoundsBracketTheBruteForceDistance) {
  std::mt19937 rng(22);
  int apart = 0;
  int touching = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const TriMesh m = randomConvexMesh(rng);
    const std::vector<Vector3d> v = verticesOf(m);
    const ConvexBracket br = buildConvexBracket(m);
    Vector3d t[3];
    const Vector3d centre = randomTriangleNearBody(rng, t);
    const DistanceBounds pb = pointConvexBracketBounds(centre, br.a_m, br.b_m, br.outer_radius_m, br.inner_radius_m);
    const double point_brute = bruteForcePointDistance(centre, m);
    EXPECT_LE(pb.lower_m, point_brute + 1e-12) << "trial " << trial;
    EXPECT_GE(pb.upper_m, point_brute - 1e-12) << "trial " << trial;
    if (pb.lower_m > 0.0) {
      for (const Vector3d& q : v) EXPECT_GE(pb.axis.dot(centre - q), pb.lower_m - 1e-12) << "trial " << trial;
    }
    const DistanceBounds tb =
        triangleConvexBracketBounds(t[0], t[1], t[2], br.a_m, br.b_m, br.outer_radius_m, br.inner_radius_m);
    const double brute = bruteForceDistance(t, m);
    EXPECT_LE(tb.lower_m, brute + 1e-12) << "trial " << trial;
    EXPECT_GE(tb.upper_m, brute - 1e-12) << "trial " << trial;
    const double segment_distance = segmentTriangleDistanceBySearch(br.a_m, br.b_m, t);
    if (segment_distance > br.inner_radius_m) {
      EXPECT_NEAR(tb.upper_m, segment_distance - br.inner_radius_m, 1e-9) << "trial " << trial;
    } else {
      EXPECT_EQ(tb.upper_m, 0.0) << "trial " << trial;
    }
    if (tb.lower_m > 0.0) {
      EXPECT_NEAR(tb.lower_m, segment_distance - br.outer_radius_m, 1e-9) << "trial " << trial;
      for (const Vector3d& p : t) {
        for (const Vector3d& q : v) EXPECT_GE(tb.axis.dot(p - q), tb.lower_m - 1e-12) << "trial " << trial;
      }
      ++apart;
    } else if (brute == 0.0) {
      ++touching;
    }
  }
  EXPECT_GT(apart, 150);
  EXPECT_GT(touching, 10);
}

// The table's start vertices: a vertex that some triangle uses (also when vertex 0 is an
// isolated interior point), near the top along the looked-up direction (within the cell's
// angular size of the brute-force maximum: the climb from it is short), and the climb from it
// exact.
TEST(ConvexDistanceTest, SupportTableStartsNearTheFarthestVertex) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 100; ++trial) {
    const TriMesh base = randomConvexMesh(rng);
    std::vector<Vector3d> vertices{Vector3d::Zero()};
    for (int v = 0; v < base.numVertices(); ++v) vertices.push_back(base.vertex(v));
    std::vector<Eigen::Vector3i> triangles;
    for (int t = 0; t < base.numTriangles(); ++t) triangles.push_back(base.triangle(t) + Eigen::Vector3i::Ones());
    const TriMesh m = TriMesh::build("convex mesh with an unused vertex 0", vertices, triangles);
    const SupportTable table = buildSupportTable(m, kSupportTableCells);
    const VertexGraph graph = buildVertexGraph(m);
    const std::vector<Vector3d> v = verticesOf(m);
    double extent = 0.0;
    for (const Vector3d& p : v) extent = std::max(extent, p.norm());
    for (int k = 0; k < 50; ++k) {
      const Vector3d d = randomUnit(rng);
      const int start = supportTableStart(table, d);
      EXPECT_FALSE(m.vertexTriangles(start).empty()) << "trial " << trial;
      double best = -std::numeric_limits<double>::infinity();
      for (const Vector3d& p : v) best = std::max(best, p.dot(d));
      // A cell of a 6 x 6 cube face spans less than 0.5 rad: its vertex is the maximum along a
      // direction e with |e - d| < 0.5, so v_start . d >= best - 2 x 0.5 x extent.
      EXPECT_GE(v[static_cast<std::size_t>(start)].dot(d), best - extent) << "trial " << trial;
      EXPECT_EQ(v[static_cast<std::size_t>(convexSupportVertex(graph, v, d, start))].dot(d), best);
    }
  }
  EXPECT_THROW((void)buildSupportTable(makeBox({1, 1, 1}, 0.5), 0), std::invalid_argument);
}

// The direction test of the convex-link query (snch.cpp) rests on the residual of the
// projection onto the body, F(x) = x - P(x), being nonexpansive: the directions of points q
// within r of c lie within asin(r / |F(c)|) of F(c). Checked with the brute-force projection
// (nearest point over all triangles) on random convex meshes. Half the spread,
// asin(r / (2 |F(c)|)), would be wrong: the test counts the pairs that exceed it. (This checks
// the lemma; the spread used in snch.cpp is checked by the query tests against brute force.)
TEST(ConvexDistanceTest, ProjectionResidualIsNonexpansive) {
  std::mt19937 rng(24);
  const auto residual = [](const Vector3d& x, const TriMesh& m) {
    Vector3d best_point = x;
    double best = std::numeric_limits<double>::infinity();
    for (int f = 0; f < m.numTriangles(); ++f) {
      const auto& tri = m.triangle(f);
      const PointTriangleResult r = closestPointTriangle(x, m.vertex(tri[0]), m.vertex(tri[1]), m.vertex(tri[2]));
      if (r.distance_m < best) {
        best = r.distance_m;
        best_point = r.point;
      }
    }
    return Vector3d(x - best_point);
  };
  int beyond_half_spread = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const TriMesh m = randomConvexMesh(rng);
    const ConvexBracket br = buildConvexBracket(m);
    const Vector3d mid = 0.5 * (br.a_m + br.b_m);
    const Vector3d c = mid +
                       (br.outer_radius_m + std::uniform_real_distribution<double>(0.005, 0.1)(rng)) * randomUnit(rng) +
                       std::uniform_real_distribution<double>(-0.5, 0.5)(rng) * (br.b_m - br.a_m);
    if (bruteForcePointDistance(c, m) == 0.0) continue;
    const Vector3d fc = residual(c, m);
    const double d = fc.norm();
    for (int k = 0; k < 10; ++k) {
      const double r = std::uniform_real_distribution<double>(0.0, 0.95)(rng) * d;
      const Vector3d q = c + r * randomUnit(rng);
      if (bruteForcePointDistance(q, m) == 0.0) continue;
      const Vector3d fq = residual(q, m);
      EXPECT_LE((fq - fc).norm(), (q - c).norm() + 1e-12) << "trial " << trial;
      const double angle = std::atan2(fq.cross(fc).norm(), fq.dot(fc));
      EXPECT_LE(angle, std::asin(std::min(1.0, (q - c).norm() / d)) + 1e-9) << "trial " << trial;
      if (angle > std::asin(std::min(1.0, (q - c).norm() / (2.0 * d)))) ++beyond_half_spread;
    }
  }
  EXPECT_GT(beyond_half_spread, 100);
}

// NaN input (a NaN pose or vertex) must not read as "proven far apart": the bracket kernels
// then return bounds that prune nothing (lower 0, upper infinity).
TEST(ConvexDistanceTest, BracketBoundsOfNanInputPruneNothing) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const Vector3d a(0, 0, 0);
  const Vector3d b(0, 0, 0.3);
  const Vector3d bad(nan, 0.2, 0.1);
  for (const DistanceBounds& db :
       {pointConvexBracketBounds(bad, a, b, 0.05, 0.048),
        pointConvexBracketBounds(Vector3d(0.5, 0, 0), a, Vector3d(0, nan, 0.3), 0.05, 0.048),
        triangleConvexBracketBounds(bad, Vector3d(0.5, 0, 0), Vector3d(0.5, 0.1, 0), a, b, 0.05, 0.048),
        triangleConvexBracketBounds(Vector3d(0.5, 0, 0), Vector3d(0.5, 0.1, 0), Vector3d(0.5, 0, 0.1), a,
                                    Vector3d(nan, 0, 0.3), 0.05, 0.048)}) {
    EXPECT_EQ(db.lower_m, 0.0);
    EXPECT_EQ(db.upper_m, std::numeric_limits<double>::infinity());
  }
  // The same kernels on finite input: a real separation (the control).
  const DistanceBounds far = pointConvexBracketBounds(Vector3d(0.5, 0, 0.1), a, b, 0.05, 0.048);
  EXPECT_NEAR(far.lower_m, 0.45, 1e-12);
  EXPECT_NEAR(far.upper_m, 0.452, 1e-12);
}

TEST(ConvexDistanceTest, KernelsDoNotAllocate) {
  const TriMesh m = makeCapsule({0, 0, 0}, {0, 0, 0.3}, 0.05, 16, 4);
  const std::vector<Vector3d> v = verticesOf(m);
  const VertexGraph graph = buildVertexGraph(m);
  int warm = 0;
  int s = 0;
  DistanceBounds b;
  EXPECT_NO_HEAP_ALLOCATION(s = convexSupportVertex(graph, v, Vector3d(0.3, -0.2, 0.9).normalized(), 0));
  EXPECT_NO_HEAP_ALLOCATION(b = triangleConvexMeshDistanceBounds(Vector3d(0.1, 0, 0.1), Vector3d(0.1, 0.05, 0.12),
                                                                 Vector3d(0.12, 0, 0.2), graph, v, 1.0, 1e-9, warm));
  const ConvexBracket br = buildConvexBracket(m);
  const SupportTable table = buildSupportTable(m, kSupportTableCells);
  DistanceBounds pb;
  DistanceBounds tb;
  int start = -1;
  EXPECT_NO_HEAP_ALLOCATION(
      pb = pointConvexBracketBounds(Vector3d(0.1, 0, 0.1), br.a_m, br.b_m, br.outer_radius_m, br.inner_radius_m));
  EXPECT_NO_HEAP_ALLOCATION(tb = triangleConvexBracketBounds(Vector3d(0.1, 0, 0.1), Vector3d(0.1, 0.05, 0.12),
                                                             Vector3d(0.12, 0, 0.2), br.a_m, br.b_m, br.outer_radius_m,
                                                             br.inner_radius_m));
  EXPECT_NO_HEAP_ALLOCATION(start = supportTableStart(table, Vector3d(0.3, -0.2, 0.9)));
  EXPECT_NEAR(pb.lower_m, 0.05, 1e-9);  // the outer capsule is the capsule: 0.1 - 0.05
  EXPECT_NEAR(tb.lower_m, 0.05, 1e-9);
  EXPECT_GE(start, 0);
  EXPECT_GE(s, 0);
  EXPECT_GT(b.lower_m, 0.04);  // the capsule's side at x = 0.05 (inscribed: up to 1 % in)
  EXPECT_LT(b.upper_m, 0.0501);
}

}  // namespace
}  // namespace fullarm::haptics
