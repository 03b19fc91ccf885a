// Closest points: against FCL's triangle distance (PQP algorithm), dense sampling, and
// analytic configurations for each feature class, parallel and intersecting cases.
#include "fullarm/haptics/geometry.hpp"

#include <gtest/gtest.h>

#include <fcl/narrowphase/detail/primitive_shape_algorithm/triangle_distance.h>

#include <array>
#include <cmath>
#include <random>

#include "segment_oracle.hpp"

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

// Nearly parallel edges (1e-5 to 1e-2 rad) passing over each other, the configuration of a
// capsule strip along a wall edge: the minimum slides far along the edges for a nanometre of
// distance, so a vertex and its closest point on the other triangle can agree with the mutual
// closest-point test to the last bit of the squared distance while the edge pair is closer
// (the general query returned up to 6e-9 m too much here before the early exit tested regions).
TEST(GeometryTest, TriangleTriangleMatchesFclWithNearlyParallelEdges) {
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> log_angle(-5.0, -2.0);
  int edge_edge = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Vector3d ea = randomPoint(rng, 1.0).normalized();
    const Vector3d side = ea.cross(randomPoint(rng, 1.0)).normalized();
    const double angle = std::pow(10.0, log_angle(rng));
    const Vector3d eb = (ea + std::tan(angle) * side).normalized();
    const Vector3d n = ea.cross(eb).normalized();
    const double h = 0.01 + 0.2 * std::abs(u(rng));
    const double shift = 0.3 * u(rng);  // the edges overlap partly, so vertices overhang edges
    std::array<Vector3d, 3> A{h * n - (0.05 + std::abs(u(rng))) * ea, h * n + (0.05 + std::abs(u(rng))) * ea,
                              h * n + u(rng) * ea + std::abs(u(rng)) * n + 0.3 * u(rng) * n.cross(ea)};
    std::array<Vector3d, 3> B{(shift - 0.05 - std::abs(u(rng))) * eb, (shift + 0.05 + std::abs(u(rng))) * eb,
                              u(rng) * eb - std::abs(u(rng)) * n + 0.3 * u(rng) * n.cross(eb)};
    const TriangleTriangleResult r = closestPointsTriangleTriangle(A[0], A[1], A[2], B[0], B[1], B[2]);
    Vector3d P;
    Vector3d Q;
    const double d_fcl = fcl::detail::TriangleDistance<double>::triDistance(A[0], A[1], A[2], B[0], B[1], B[2], P, Q);
    ASSERT_NEAR(r.distance_m, d_fcl, kTol) << "trial " << trial << ", angle " << angle << " rad";
    EXPECT_NEAR((r.p - r.q).norm(), r.distance_m, kTol);
    expectOnFeature(r.p, A, r.feature_a);
    expectOnFeature(r.q, B, r.feature_b);
    if (r.feature_a.kind == Kind::kEdge && r.feature_b.kind == Kind::kEdge) ++edge_edge;
  }
  EXPECT_GT(edge_edge, 5000);  // the sliding edge-edge minima were exercised
  RecordProperty("edge_edge", edge_edge);
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

// The warm-started query from every guess pair of features (the true pair included): the
// reference distance d_ref (kTol), points that far apart and on the reported features.
void expectWarmStartsMatch(const PreparedTriangle& pa, const PreparedTriangle& pb, const std::array<Vector3d, 3>& A,
                           const std::array<Vector3d, 3>& B, double d_ref, int trial) {
  for (const LocalFeature& ga : allLocalFeatures()) {
    for (const LocalFeature& gb : allLocalFeatures()) {
      const TriangleTriangleResult w = closestPointsTriangleTriangleWarm(pa, pb, ga, gb);
      ASSERT_NEAR(w.distance_m, d_ref, kTol) << "trial " << trial;
      EXPECT_NEAR((w.p - w.q).norm(), w.distance_m, kTol);
      expectOnFeature(w.p, A, w.feature_a);
      expectOnFeature(w.q, B, w.feature_b);
    }
  }
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
    // Warm start from every guess pair, including the true one.
    ASSERT_NO_FATAL_FAILURE(expectWarmStartsMatch(pa, pb, A, B, d_fcl, trial));
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

// Reference for the spanning-segment kernel: the general segment-triangle distance composed from
// the public primitives (segment against each edge, each endpoint against the triangle), valid
// when the segment does not cross the triangle; and whether it crosses (plane test).
struct SegmentTriangleReference {
  double distance_m;
  bool crosses;
};

SegmentTriangleReference segmentTriangleReference(const Vector3d& p0, const Vector3d& p1,
                                                  const std::array<Vector3d, 3>& t) {
  double d = std::min(closestPointTriangle(p0, t[0], t[1], t[2]).distance_m,
                      closestPointTriangle(p1, t[0], t[1], t[2]).distance_m);
  for (int j = 0; j < 3; ++j) {
    d = std::min(d, closestPointsSegmentSegment(p0, p1, t[j], t[(j + 1) % 3]).distance_m);
  }
  const Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
  const double h0 = n.dot(p0 - t[0]);
  const double h1 = n.dot(p1 - t[0]);
  bool crosses = false;
  if ((h0 <= 0.0) != (h1 <= 0.0)) {
    const Vector3d x = p0 + (h0 / (h0 - h1)) * (p1 - p0);
    crosses = true;
    for (int k = 0; k < 3; ++k) crosses = crosses && n.dot((t[(k + 1) % 3] - t[k]).cross(x - t[k])) >= 0.0;
  }
  return {crosses ? 0.0 : d, crosses};
}

// The kernel that local descent uses for a long link edge over a small object triangle,
// against the general query on random and degenerate configurations: (0) general position,
// (1) a triangle edge parallel to the segment, (2) the line passing over (or through) a
// vertex, (3) the segment in the triangle's plane, (4) the triangle's plane containing the
// segment's direction (the projected triangle is a segment), (5) the segment crossing the
// triangle, (6) a segment too short to span the triangle.
TEST(GeometryTest, SpanningSegmentKernelMatchesGeneralSegmentTriangle) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<int, 7> applied{};
  std::array<int, 7> declined{};
  int sampled = 0;
  for (int trial = 0; trial < 21000; ++trial) {
    const int family = trial % 7;
    // A triangle of ~1 cm and a segment of ~0.3 m along a random direction e through a point
    // near it, offset by up to 2 cm perpendicular to e.
    const Vector3d e = randomPoint(rng, 1.0).normalized();
    std::array<Vector3d, 3> t{randomPoint(rng, 0.01), randomPoint(rng, 0.01), randomPoint(rng, 0.01)};
    Vector3d offset = randomPoint(rng, 0.02);
    if (family == 1) t[1] = t[0] + 0.01 * u(rng) * e;
    if (family == 2) offset = t[static_cast<std::size_t>(trial % 3)] + (trial % 2 == 0 ? 0.0 : 0.005) * offset;
    if (family == 3 || family == 4) {
      // Triangle in a plane containing e: t = c + a e + b m with m perpendicular to e.
      const Vector3d m = e.cross(randomPoint(rng, 1.0)).normalized();
      for (Vector3d& v : t) v = 0.01 * (u(rng) * e + u(rng) * m);
      offset = 0.02 * u(rng) * m;
      if (family == 4) offset += 0.01 * u(rng) * e.cross(m);
    }
    if (family == 5) offset = (t[0] + t[1] + t[2]) / 3.0 + 0.001 * randomPoint(rng, 1.0);
    offset -= offset.dot(e) * e;
    const double half_length = family == 6 ? 0.004 : 0.15 + 0.1 * u(rng);
    const Vector3d p0 = offset - (half_length + 0.002 * u(rng)) * e;
    const Vector3d p1 = offset + (half_length + 0.002 * u(rng)) * e;
    if (((t[1] - t[0]).cross(t[2] - t[0])).squaredNorm() < 1e-16) continue;  // degenerate triangle
    const PreparedTriangle pt = prepareTriangle(t[0], t[1], t[2]);
    const Vector3d d = p1 - p0;
    SegmentTriangleResult r;
    const bool ok = closestPointsSpanningSegmentTriangle(p0, d, d.squaredNorm(), pt, r);
    const SegmentTriangleReference ref = segmentTriangleReference(p0, p1, t);
    bool spans = true;
    for (const Vector3d& v : t) spans = spans && (v - p0).dot(d) >= 0.0 && (v - p0).dot(d) <= d.squaredNorm();
    if (!ok) {
      ++declined[static_cast<std::size_t>(family)];
      // Declining is always safe (the general query runs), but in general position and over
      // a vertex it happens only off the kernel's domain: not spanning, crossing or touching.
      // (Families 1, 3 and 4 project an edge or the whole triangle onto a segment, where the
      // rounding of the region tests may reach the face region: declined, counted below.)
      EXPECT_TRUE(!spans || ref.crosses || family == 1 || family == 3 || family == 4 || ref.distance_m < 1e-12)
          << "trial " << trial << " declined a spanning, non-crossing configuration";
      continue;
    }
    ++applied[static_cast<std::size_t>(family)];
    SCOPED_TRACE("trial " + std::to_string(trial) + " family " + std::to_string(family));
    EXPECT_TRUE(spans) << "trial " << trial;
    ASSERT_FALSE(ref.crosses && ref.distance_m == 0.0 && r.distance_sq > 1e-20) << "trial " << trial;
    const double dist = std::sqrt(r.distance_sq);
    ASSERT_NEAR(dist, ref.distance_m, kTol) << "trial " << trial << " family " << family;
    EXPECT_NEAR((r.p - r.q).squaredNorm(), r.distance_sq, 1e-24);
    EXPECT_GE(r.s, 0.0);
    EXPECT_LE(r.s, 1.0);
    EXPECT_LT((p0 + r.s * d - r.p).norm(), 1e-15);
    ASSERT_NE(r.feature_t.kind, Kind::kFace);
    EXPECT_LT(closestPointTriangle(r.q, t[0], t[1], t[2]).distance_m, 1e-13);  // q on the triangle
    // The feature holds q in its relative interior (at contact, distance ~0 along the line
    // through a vertex, which feature is a matter of rounding).
    if (dist > 1e-9) expectOnFeature(r.q, t, r.feature_t);
    // Brute force: no sampled point of the segment is closer to the triangle.
    if (trial % 10 == 0) {
      ++sampled;
      for (int k = 0; k <= 200; ++k) {
        const Vector3d x = p0 + (k / 200.0) * d;
        EXPECT_GE(closestPointTriangle(x, t[0], t[1], t[2]).distance_m, dist - kTol) << "trial " << trial;
      }
    }
  }
  // Every family except the crossing and the short segments mostly runs the kernel.
  for (const int f : {0, 1, 2, 3, 4}) EXPECT_GT(applied[static_cast<std::size_t>(f)], 1000) << "family " << f;
  EXPECT_GT(declined[5], 2000);  // crossing: the face region declines
  EXPECT_GT(declined[6], 2000);  // short segments do not span
  EXPECT_GT(sampled, 1000);
}

// The exact segment-triangle query (the capsule links' primitive) against the long-double
// oracle (golden section over the segment parameter) on random and special configurations: (0)
// general position, (1) the segment parallel to a triangle edge, (2) the segment's line through
// a vertex, (3) the segment in the triangle's plane, (4) parallel to the plane above it, (5)
// crossing the triangle, (6) a segment of zero length. The distance agrees within 1e-12 m, the
// points lie at that distance on the segment and the triangle, q on the reported feature, and a
// crossing gives 0.
TEST(GeometryTest, SegmentTriangleMatchesTheLongDoubleOracle) {
  std::mt19937 rng(57);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::array<int, 3> features{};
  int crossings = 0;
  for (int trial = 0; trial < 14000; ++trial) {
    const int family = trial % 7;
    std::array<Vector3d, 3> t{randomPoint(rng, 0.05), randomPoint(rng, 0.05), randomPoint(rng, 0.05)};
    const Vector3d n = (t[1] - t[0]).cross(t[2] - t[0]);
    if (n.squaredNorm() < 1e-12) continue;
    const Vector3d nu = n.normalized();
    Vector3d p0 = randomPoint(rng, 0.1);
    Vector3d p1 = randomPoint(rng, 0.1);
    if (family == 1) p1 = p0 + 2.0 * u(rng) * (t[1] - t[0]);
    if (family == 2) p1 = t[0] + 0.5 * u(rng) * (t[0] - p0) + (t[0] - p0);
    if (family == 3) {
      p0 -= nu.dot(p0 - t[0]) * nu;
      p1 -= nu.dot(p1 - t[0]) * nu;
    }
    if (family == 4) p1 -= nu.dot(p1 - p0) * nu;
    if (family == 5) {
      const Vector3d inside = (t[0] + t[1] + t[2]) / 3.0;
      const Vector3d dir = randomPoint(rng, 1.0);
      p0 = inside + 0.1 * dir;
      p1 = inside - (0.05 + 0.05 * std::abs(u(rng))) * dir;
    }
    if (family == 6) p1 = p0;
    const SegmentTriangleResult r = closestPointsSegmentTriangle(p0, p1, prepareTriangle(t[0], t[1], t[2]));
    const long double oracle = test::segmentTriangleOracle(test::toLong(p0), test::toLong(p1), test::toLong(t[0]),
                                                           test::toLong(t[1]), test::toLong(t[2]));
    SCOPED_TRACE("trial " + std::to_string(trial) + " family " + std::to_string(family));
    const double dist = std::sqrt(r.distance_sq);
    ASSERT_NEAR(dist, static_cast<double>(oracle), kTol);
    EXPECT_NEAR((r.p - r.q).squaredNorm(), r.distance_sq, 1e-24);
    EXPECT_GE(r.s, 0.0);
    EXPECT_LE(r.s, 1.0);
    EXPECT_LT((p0 + r.s * (p1 - p0) - r.p).norm(), 1e-15);
    EXPECT_LT(closestPointTriangle(r.q, t[0], t[1], t[2]).distance_m, 1e-13);  // q on the triangle
    if (dist > 1e-9) expectOnFeature(r.q, t, r.feature_t);
    if (family == 5) {
      EXPECT_EQ(r.distance_sq, 0.0);
      crossings += r.distance_sq == 0.0 ? 1 : 0;
    }
    ++features[static_cast<std::size_t>(r.feature_t.kind)];
  }
  EXPECT_GT(crossings, 1900);
  for (int k = 0; k < 3; ++k) EXPECT_GT(features[static_cast<std::size_t>(k)], 1000) << k;
}

// The warm start of a long edge (a link capsule's strip) against small triangles, the path of
// local descent's object-side neighbour evaluations, against FCL's triangle distance.
TEST(GeometryTest, WarmStartOfLongEdgesOverSmallTrianglesMatchesFcl) {
  std::mt19937 rng(37);
  int spanning = 0;
  int raw_decided = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const Vector3d e = randomPoint(rng, 1.0).normalized();
    const Vector3d m = e.cross(randomPoint(rng, 1.0)).normalized();
    // A: a strip triangle, edge 0 of length 0.3 m along e, its third vertex 1 cm aside.
    const Vector3d a0 = randomPoint(rng, 0.02) - 0.15 * e;
    const std::array<Vector3d, 3> A{a0, a0 + 0.3 * e, a0 + 0.3 * e + 0.01 * m};
    // B: a ~1 cm triangle near the middle of the strip edge, some nearly parallel to it.
    std::array<Vector3d, 3> B{randomPoint(rng, 0.01), randomPoint(rng, 0.01), randomPoint(rng, 0.01)};
    if (trial % 3 == 0) {
      for (Vector3d& v : B) v -= (v.dot(m.cross(e)) - 0.003) * m.cross(e);  // in a plane parallel to e and m
    }
    const PreparedTriangle pa = prepareTriangle(A[0], A[1], A[2]);
    const PreparedTriangle pb = prepareTriangle(B[0], B[1], B[2]);
    if (!(pb.normal_sq > 1e-16)) continue;
    SegmentTriangleResult probe;
    spanning += closestPointsSpanningSegmentTriangle(pa.v[0], pa.edge[0], pa.edge_sq[0], pb, probe) ? 1 : 0;
    // The raw-vertex evaluation of local descent: bit for bit the warm start on the prepared
    // triangle whenever it decides.
    for (int k = 0; k < 3; ++k) {
      TriangleTriangleResult raw;
      if (!closestPointsEdgeTriangleSpanning(pa, k, B[0], B[1], B[2], raw)) continue;
      ++raw_decided;
      const TriangleTriangleResult w =
          closestPointsTriangleTriangleWarm(pa, pb, LocalFeature{Kind::kEdge, static_cast<std::uint8_t>(k)}, {});
      EXPECT_EQ(raw.distance_m, w.distance_m);
      EXPECT_EQ(raw.p, w.p);
      EXPECT_EQ(raw.q, w.q);
      EXPECT_EQ(raw.feature_a.kind, w.feature_a.kind);
      EXPECT_EQ(raw.feature_a.index, w.feature_a.index);
      EXPECT_EQ(raw.feature_b.kind, w.feature_b.kind);
      EXPECT_EQ(raw.feature_b.index, w.feature_b.index);
    }
    Vector3d P;
    Vector3d Q;
    const double d_fcl = fcl::detail::TriangleDistance<double>::triDistance(A[0], A[1], A[2], B[0], B[1], B[2], P, Q);
    ASSERT_NO_FATAL_FAILURE(expectWarmStartsMatch(pa, pb, A, B, d_fcl, trial));
  }
  EXPECT_GT(spanning, 2000);
  EXPECT_GT(raw_decided, 1000);
}

// The raw-vertex optimality certificates that local descent checks before preparing the tracked
// pair's triangles: sound against FCL's triangle distance (a certified pair has FCL's distance,
// points on the certified features) and complete against the general query (a
// pair whose general minimum is that edge-edge or vertex-face pair, away from region
// boundaries, is certified). Random pairs, pairs built around two crossing edges (the
// edge-edge case), and nearly parallel edges.
TEST(GeometryTest, CertificatesAgreeWithTheGeneralQuery) {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int ee_certified = 0;
  int ee_expected = 0;
  int ee_complete = 0;
  int vt_certified = 0;
  int vt_expected = 0;
  int vt_complete = 0;
  for (int trial = 0; trial < 6000; ++trial) {
    std::array<Vector3d, 3> A{randomPoint(rng, 1.0), randomPoint(rng, 1.0), randomPoint(rng, 1.0)};
    std::array<Vector3d, 3> B{randomPoint(rng, 1.0), randomPoint(rng, 1.0), randomPoint(rng, 1.0)};
    if (trial % 3 == 1) {
      // Edge A0A1 crossing over edge B0B1 at height h along n = ea x eb, third vertices away.
      const Vector3d ea = randomPoint(rng, 1.0).normalized();
      const Vector3d eb = (trial % 6 == 1 ? (ea + 1e-3 * randomPoint(rng, 1.0)) : randomPoint(rng, 1.0)).normalized();
      const Vector3d n = ea.cross(eb).normalized();
      const double h = 0.01 + 0.2 * std::abs(u(rng));
      A[0] = h * n - (0.2 + std::abs(u(rng))) * ea;
      A[1] = h * n + (0.2 + std::abs(u(rng))) * ea;
      A[2] = h * n + u(rng) * ea + std::abs(u(rng)) * n + 0.3 * u(rng) * n.cross(ea);
      B[0] = -(0.2 + std::abs(u(rng))) * eb;
      B[1] = (0.2 + std::abs(u(rng))) * eb;
      B[2] = u(rng) * eb - std::abs(u(rng)) * n + 0.3 * u(rng) * n.cross(eb);
    } else if (trial % 3 == 2) {
      for (Vector3d& v : B) v += Vector3d(0.0, 0.0, 2.5);  // apart: mostly vertex-face minima
    }
    const PreparedTriangle pa = prepareTriangle(A[0], A[1], A[2]);
    const PreparedTriangle pb = prepareTriangle(B[0], B[1], B[2]);
    if (!(pa.normal_sq > 1e-12 && pb.normal_sq > 1e-12)) continue;
    const TriangleTriangleResult g = closestPointsTriangleTriangle(pa, pb);
    if (g.intersecting) continue;
    Vector3d P;
    Vector3d Q;
    const double d_fcl = fcl::detail::TriangleDistance<double>::triDistance(A[0], A[1], A[2], B[0], B[1], B[2], P, Q);
    const double g_sq = d_fcl * d_fcl;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        Vector3d p;
        Vector3d q;
        double d_sq = 0.0;
        const bool ok = certifyEdgeEdgePair(A[i], A[(i + 1) % 3], pa.normal.cross(pa.edge[i]), B[j], B[(j + 1) % 3],
                                            pb.normal.cross(pb.edge[j]), p, q, d_sq);
        const bool general_pair = g.feature_a.kind == Kind::kEdge && g.feature_a.index == i &&
                                  g.feature_b.kind == Kind::kEdge && g.feature_b.index == j;
        if (general_pair) ++ee_expected;
        if (!ok) continue;
        ++ee_certified;
        if (general_pair) ++ee_complete;
        ASSERT_NEAR(d_sq, g_sq, 1e-12 * std::max(1.0, g_sq)) << "trial " << trial << " edges " << i << j;
        EXPECT_NEAR((p - q).squaredNorm(), d_sq, 1e-14);
        expectOnFeature(p, A, LocalFeature{Kind::kEdge, static_cast<std::uint8_t>(i)});
        expectOnFeature(q, B, LocalFeature{Kind::kEdge, static_cast<std::uint8_t>(j)});
      }
    }
    for (int k = 0; k < 3; ++k) {
      Vector3d q;
      double d_sq = 0.0;
      LocalFeature f;
      const bool ok = certifyVertexTriangle(B[k], B[(k + 1) % 3] - B[k], B[(k + 2) % 3] - B[k], pa, q, d_sq, f);
      const bool general_pair = g.feature_b.kind == Kind::kVertex && g.feature_b.index == k;
      if (general_pair) ++vt_expected;
      if (!ok) continue;
      ++vt_certified;
      if (general_pair) ++vt_complete;
      ASSERT_NEAR(d_sq, g_sq, 1e-12 * std::max(1.0, g_sq)) << "trial " << trial << " vertex " << k;
      expectOnFeature(q, A, f);
      EXPECT_NEAR((q - B[k]).squaredNorm(), d_sq, 1e-14);
    }
  }
  // Complete: the general minimum's own pair is certified (ties with another equally close
  // representative are the only exception); and both certificates are exercised.
  EXPECT_GT(ee_expected, 1500);
  EXPECT_GE(ee_complete, ee_expected * 99 / 100) << ee_complete << " of " << ee_expected;
  EXPECT_GT(vt_expected, 1500);
  EXPECT_GE(vt_complete, vt_expected * 99 / 100) << vt_complete << " of " << vt_expected;
  EXPECT_GE(ee_certified, ee_complete);
  EXPECT_GE(vt_certified, vt_complete);
}

}  // namespace
}  // namespace fullarm::haptics
