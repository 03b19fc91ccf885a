// Closest points: against FCL's triangle distance (PQP algorithm), dense sampling, and
// analytic configurations for each feature class, parallel and intersecting cases.
#include "fullarm/haptics/geometry.hpp"

#include <gtest/gtest.h>

#include <fcl/narrowphase/detail/primitive_shape_algorithm/triangle_distance.h>

#include <array>
#include <random>

namespace fullarm::haptics {
namespace {

using Eigen::Vector3d;
using Kind = LocalFeature::Kind;

constexpr double kTol = 1e-12;

Vector3d randomPoint(std::mt19937& rng, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  return {u(rng), u(rng), u(rng)};
}

// The reported feature must be the one whose relative interior holds the point.
void expectOnFeature(const Vector3d& x, const std::array<Vector3d, 3>& t, const LocalFeature& f) {
  switch (f.kind) {
    case Kind::kVertex:
      EXPECT_LT((x - t[f.index]).norm(), 1e-12);
      break;
    case Kind::kEdge: {
      const Vector3d& a = t[f.index];
      const Vector3d& b = t[(f.index + 1) % 3];
      const double s = (x - a).dot(b - a) / (b - a).squaredNorm();
      EXPECT_GT(s, 0.0);
      EXPECT_LT(s, 1.0);
      EXPECT_LT((a + s * (b - a) - x).norm(), 1e-10);
      break;
    }
    case Kind::kFace: {
      const Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
      EXPECT_LT(std::abs(n.normalized().dot(x - t[0])), 1e-10);
      for (int k = 0; k < 3; ++k) EXPECT_GE(n.dot((t[(k + 1) % 3] - t[k]).cross(x - t[k])), 0.0);
      break;
    }
  }
}

TEST(GeometryTest, TriangleTriangleMatchesFclOnRandomPairs) {
  std::mt19937 rng(7);
  int intersecting = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const double spread = trial % 4 == 0 ? 0.3 : 1.5;
    std::array<Vector3d, 3> A{randomPoint(rng, 1.0), randomPoint(rng, 1.0), randomPoint(rng, 1.0)};
    const Vector3d shift = randomPoint(rng, spread);
    std::array<Vector3d, 3> B{randomPoint(rng, 1.0) + shift, randomPoint(rng, 1.0) + shift,
                              randomPoint(rng, 1.0) + shift};
    const TriangleTriangleResult r = closestPointsTriangleTriangle(A[0], A[1], A[2], B[0], B[1], B[2]);
    Vector3d P;
    Vector3d Q;
    const double d_fcl = fcl::detail::TriangleDistance<double>::triDistance(A[0], A[1], A[2], B[0], B[1], B[2], P, Q);
    ASSERT_NEAR(r.distance_m, d_fcl, kTol) << "trial " << trial;
    EXPECT_NEAR((r.p - r.q).norm(), r.distance_m, kTol);
    if (r.intersecting) {
      ++intersecting;
      EXPECT_EQ(r.distance_m, 0.0);
    }
    expectOnFeature(r.p, A, r.feature_a);
    expectOnFeature(r.q, B, r.feature_b);
  }
  EXPECT_GT(intersecting, 100);
}

TEST(GeometryTest, PointTriangleMatchesDenseSampling) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 200; ++trial) {
    const std::array<Vector3d, 3> T{randomPoint(rng, 1.0), randomPoint(rng, 1.0), randomPoint(rng, 1.0)};
    const Vector3d p = randomPoint(rng, 2.0);
    const PointTriangleResult r = closestPointTriangle(p, T[0], T[1], T[2]);
    // Dense barycentric grid: the exact distance is a lower bound, and within the grid spacing.
    constexpr int kN = 300;
    double best = std::numeric_limits<double>::infinity();
    for (int i = 0; i <= kN; ++i) {
      for (int j = 0; i + j <= kN; ++j) {
        const double a = static_cast<double>(i) / kN;
        const double b = static_cast<double>(j) / kN;
        best = std::min(best, (p - ((1 - a - b) * T[0] + a * T[1] + b * T[2])).norm());
      }
    }
    const double h = std::max({(T[1] - T[0]).norm(), (T[2] - T[0]).norm(), (T[2] - T[1]).norm()}) / kN;
    EXPECT_LE(r.distance_m, best + 1e-15);
    EXPECT_GE(r.distance_m, best - h);
    expectOnFeature(r.point, T, r.feature);
    EXPECT_NEAR(squaredDistancePointTriangle(p, T[0], T[1], T[2]), r.distance_m * r.distance_m, 1e-14);
  }
}

TEST(GeometryTest, AnalyticFeatureClasses) {
  const Vector3d a(0, 0, 0), b(1, 0, 0), c(0, 1, 0);
  // Vertex above the face interior: face / vertex.
  auto r = closestPointsTriangleTriangle(a, b, c, {0.2, 0.2, 0.5}, {0.3, 0.3, 2.0}, {0.1, 0.4, 2.0});
  EXPECT_NEAR(r.distance_m, 0.5, kTol);
  EXPECT_EQ(r.feature_a.kind, Kind::kFace);
  EXPECT_EQ(r.feature_b.kind, Kind::kVertex);
  EXPECT_EQ(r.feature_b.index, 0);
  // Crossed edges: edge / edge at the common perpendicular.
  r = closestPointsTriangleTriangle(a, b, c, {0.3, -1.0, -0.5}, {0.3, 1.0, -0.5}, {0.3, 0.0, -2.0});
  EXPECT_NEAR(r.distance_m, 0.5, kTol);
  EXPECT_EQ(r.feature_a.kind, Kind::kEdge);
  EXPECT_EQ(r.feature_a.index, 0);
  EXPECT_EQ(r.feature_b.kind, Kind::kEdge);
  EXPECT_EQ(r.feature_b.index, 0);
  EXPECT_NEAR((r.p - Vector3d(0.3, 0, 0)).norm(), 0.0, kTol);
  // Vertex to vertex.
  r = closestPointsTriangleTriangle(a, b, c, {-1, -1, -1}, {-2, -1, -1}, {-1, -2, -1});
  EXPECT_NEAR(r.distance_m, std::sqrt(3.0), kTol);
  EXPECT_EQ(r.feature_a.kind, Kind::kVertex);
  EXPECT_EQ(r.feature_b.kind, Kind::kVertex);
  // Parallel coplanar-offset faces: distance is the offset, p on A.
  r = closestPointsTriangleTriangle(a, b, c, {0.1, 0.1, 0.25}, {0.5, 0.1, 0.25}, {0.1, 0.5, 0.25});
  EXPECT_NEAR(r.distance_m, 0.25, kTol);
  EXPECT_NEAR(r.p.z(), 0.0, kTol);
  // Parallel edges (collinear overlap offset by 0.5 in z).
  r = closestPointsTriangleTriangle(a, b, c, {0.2, 0, 0.5}, {0.7, 0, 0.5}, {0.4, -0.3, 1.0});
  EXPECT_NEAR(r.distance_m, 0.5, kTol);
  // Piercing: an edge of B crosses A's interior.
  r = closestPointsTriangleTriangle(a, b, c, {0.2, 0.2, -1}, {0.2, 0.2, 1}, {2, 2, 0.5});
  EXPECT_TRUE(r.intersecting);
  EXPECT_EQ(r.distance_m, 0.0);
  EXPECT_NEAR((r.p - r.q).norm(), 0.0, kTol);
  EXPECT_NEAR(r.p.z(), 0.0, kTol);            // on A's plane
  EXPECT_NEAR(r.p.x() - r.p.y(), 0.0, kTol);  // on B's plane x = y
  // Only B pierces A: the crossing is B's edge 0 through A's face at (0.2, 0.2, 0).
  r = closestPointsTriangleTriangle(a, b, c, {0.2, 0.2, -1}, {0.2, 0.2, 1}, {0.25, 0.25, 0.5});
  EXPECT_TRUE(r.intersecting);
  EXPECT_NEAR((r.p - Vector3d(0.2, 0.2, 0)).norm(), 0.0, kTol);
  EXPECT_EQ(r.feature_a.kind, Kind::kFace);
  EXPECT_EQ(r.feature_b.kind, Kind::kEdge);
}

// Every feature of a triangle in local numbering: three vertices, three edges, the face.
std::array<LocalFeature, 7> allLocalFeatures() {
  return {LocalFeature{Kind::kVertex, 0}, LocalFeature{Kind::kVertex, 1}, LocalFeature{Kind::kVertex, 2},
          LocalFeature{Kind::kEdge, 0},   LocalFeature{Kind::kEdge, 1},   LocalFeature{Kind::kEdge, 2},
          LocalFeature{Kind::kFace, 0}};
}

TEST(GeometryTest, PreparedAndWarmStartedQueriesMatchFcl) {
  std::mt19937 rng(23);
  int intersecting = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const double spread = trial % 4 == 0 ? 0.3 : 1.5;
    std::array<Vector3d, 3> A{randomPoint(rng, 1.0), randomPoint(rng, 1.0), randomPoint(rng, 1.0)};
    const Vector3d shift = randomPoint(rng, spread);
    std::array<Vector3d, 3> B{randomPoint(rng, 1.0) + shift, randomPoint(rng, 1.0) + shift,
                              randomPoint(rng, 1.0) + shift};
    const PreparedTriangle pa = prepareTriangle(A[0], A[1], A[2]);
    const PreparedTriangle pb = prepareTriangle(B[0], B[1], B[2]);
    Vector3d P;
    Vector3d Q;
    const double d_fcl = fcl::detail::TriangleDistance<double>::triDistance(A[0], A[1], A[2], B[0], B[1], B[2], P, Q);
    const TriangleTriangleResult prepared = closestPointsTriangleTriangle(pa, pb);
    ASSERT_NEAR(prepared.distance_m, d_fcl, kTol) << "trial " << trial;
    expectOnFeature(prepared.p, A, prepared.feature_a);
    expectOnFeature(prepared.q, B, prepared.feature_b);
    intersecting += prepared.intersecting ? 1 : 0;
    // Warm start from every guess pair, including the true one: same distance, points on the
    // reported features, features a closest pair.
    for (const LocalFeature& ga : allLocalFeatures()) {
      for (const LocalFeature& gb : allLocalFeatures()) {
        const TriangleTriangleResult w = closestPointsTriangleTriangleWarm(pa, pb, ga, gb);
        ASSERT_NEAR(w.distance_m, d_fcl, kTol) << "trial " << trial;
        EXPECT_NEAR((w.p - w.q).norm(), w.distance_m, kTol);
        expectOnFeature(w.p, A, w.feature_a);
        expectOnFeature(w.q, B, w.feature_b);
      }
    }
    // Point queries on the prepared triangle against the unprepared ones (checked above
    // against dense sampling).
    const Vector3d p = randomPoint(rng, 2.0);
    const PointTriangleResult pt = closestPointTriangle(p, A[0], A[1], A[2]);
    EXPECT_NEAR(closestPointTriangle(p, pa).distance_m, pt.distance_m, kTol);
    EXPECT_NEAR(squaredDistancePointTriangle(p, pa), squaredDistancePointTriangle(p, A[0], A[1], A[2]), 1e-14);
  }
  EXPECT_GT(intersecting, 20);
}

TEST(GeometryTest, WarmStartKeepsTheGuessedPairOfParallelFeatures) {
  // Parallel faces 0.25 apart: every vertex of B above A's interior is a closest pair; the
  // warm start keeps the guessed one instead of flickering to the first in candidate order.
  const PreparedTriangle A = prepareTriangle({0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  const PreparedTriangle B = prepareTriangle({0.1, 0.1, 0.25}, {0.5, 0.1, 0.25}, {0.1, 0.5, 0.25});
  for (std::uint8_t k = 0; k < 3; ++k) {
    const TriangleTriangleResult r =
        closestPointsTriangleTriangleWarm(A, B, LocalFeature{Kind::kFace, 0}, LocalFeature{Kind::kVertex, k});
    EXPECT_NEAR(r.distance_m, 0.25, kTol);
    EXPECT_EQ(r.feature_b.kind, Kind::kVertex);
    EXPECT_EQ(r.feature_b.index, k);
    EXPECT_EQ(r.feature_a.kind, Kind::kFace);
  }
}

TEST(GeometryTest, SegmentSegmentParallelAndDegenerate) {
  auto r = closestPointsSegmentSegment({0, 0, 0}, {1, 0, 0}, {0.5, 1, 0}, {2, 1, 0});
  EXPECT_NEAR(r.distance_m, 1.0, kTol);
  r = closestPointsSegmentSegment({0, 0, 0}, {0, 0, 0}, {1, -1, 0}, {1, 1, 0});
  EXPECT_NEAR(r.distance_m, 1.0, kTol);
  EXPECT_NEAR(r.t, 0.5, kTol);
  r = closestPointsSegmentSegment({0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0});
  EXPECT_NEAR(r.distance_m, 1.0, kTol);
}

}  // namespace
}  // namespace fullarm::haptics
