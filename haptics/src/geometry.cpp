#include "fullarm/haptics/geometry.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

namespace fullarm::haptics {

using Eigen::Vector3d;
using Kind = LocalFeature::Kind;

PointTriangleResult closestPointTriangle(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                                         const Vector3d& c) noexcept {
  // Ericson, Real-Time Collision Detection, 5.1.5: test the Voronoi regions in turn.
  PointTriangleResult r;
  const Vector3d ab = b - a;
  const Vector3d ac = c - a;
  const Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  auto done = [&](const Vector3d& x, Kind kind, int index) {
    r.point = x;
    r.feature = {kind, static_cast<std::uint8_t>(index)};
    r.distance_m = (p - x).norm();
    return r;
  };
  if (d1 <= 0.0 && d2 <= 0.0) return done(a, Kind::kVertex, 0);
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return done(b, Kind::kVertex, 1);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const double v = d1 / (d1 - d3);
    return done(a + v * ab, Kind::kEdge, 0);
  }
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return done(c, Kind::kVertex, 2);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const double w = d2 / (d2 - d6);
    return done(a + w * ac, Kind::kEdge, 2);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return done(b + w * (c - b), Kind::kEdge, 1);
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom;
  const double w = vc * denom;
  return done(a + ab * v + ac * w, Kind::kFace, 0);
}

double squaredDistancePointTriangle(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                                    const Vector3d& c) noexcept {
  const Vector3d ab = b - a;
  const Vector3d ac = c - a;
  const Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return ap.squaredNorm();
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return bp.squaredNorm();
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) return (ap - (d1 / (d1 - d3)) * ab).squaredNorm();
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return cp.squaredNorm();
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) return (ap - (d2 / (d2 - d6)) * ac).squaredNorm();
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    return (bp - ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)).squaredNorm();
  }
  const double denom = 1.0 / (va + vb + vc);
  return (ap - ab * (vb * denom) - ac * (vc * denom)).squaredNorm();
}

SegmentSegmentResult closestPointsSegmentSegment(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0,
                                                 const Vector3d& q1) noexcept {
  // Ericson 5.1.9 with clamping; the parallel case picks s = 0 then clamps.
  const Vector3d d1 = p1 - p0;
  const Vector3d d2 = q1 - q0;
  const Vector3d r = p0 - q0;
  const double a = d1.squaredNorm();
  const double e = d2.squaredNorm();
  const double f = d2.dot(r);
  double s = 0.0;
  double t = 0.0;
  constexpr double kTiny = 1e-300;
  if (a <= kTiny && e <= kTiny) {
    s = t = 0.0;
  } else if (a <= kTiny) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = d1.dot(r);
    if (e <= kTiny) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = d1.dot(d2);
      const double denom = a * e - b * b;
      // Relative parallelism test: sin^2 of the angle below 1e-20.
      s = denom > 1e-20 * a * e ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0.0) {
        t = 0.0;
        s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1.0) {
        t = 1.0;
        s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  SegmentSegmentResult out;
  out.s = s;
  out.t = t;
  out.p = p0 + s * d1;
  out.q = q0 + t * d2;
  out.distance_m = (out.p - out.q).norm();
  return out;
}

namespace {

// Intersection of segment [p0, p1] with triangle (a, b, c): true and the crossing parameter
// when the open-or-closed segment meets the closed triangle at one point (coplanar overlaps
// are left to the distance candidates, which then find distance 0).
bool segmentTriangleCrossing(const Vector3d& p0, const Vector3d& p1, const Vector3d& a, const Vector3d& b,
                             const Vector3d& c, double& s_out) noexcept {
  const Vector3d n = (b - a).cross(c - a);
  const double h0 = n.dot(p0 - a);
  const double h1 = n.dot(p1 - a);
  if ((h0 > 0.0 && h1 > 0.0) || (h0 < 0.0 && h1 < 0.0) || h0 == h1) return false;
  const double s = h0 / (h0 - h1);
  const Vector3d x = p0 + s * (p1 - p0);
  // Inside test by signed areas against the normal.
  if (n.dot((b - a).cross(x - a)) < 0.0) return false;
  if (n.dot((c - b).cross(x - b)) < 0.0) return false;
  if (n.dot((a - c).cross(x - c)) < 0.0) return false;
  s_out = s;
  return true;
}

LocalFeature edgeFeature(int k, double s) noexcept {
  if (s <= 0.0) return {Kind::kVertex, static_cast<std::uint8_t>(k)};
  if (s >= 1.0) return {Kind::kVertex, static_cast<std::uint8_t>((k + 1) % 3)};
  return {Kind::kEdge, static_cast<std::uint8_t>(k)};
}

}  // namespace

TriangleTriangleResult closestPointsTriangleTriangle(const Vector3d& a0, const Vector3d& a1, const Vector3d& a2,
                                                     const Vector3d& b0, const Vector3d& b1,
                                                     const Vector3d& b2) noexcept {
  const std::array<const Vector3d*, 3> A{&a0, &a1, &a2};
  const std::array<const Vector3d*, 3> B{&b0, &b1, &b2};
  TriangleTriangleResult best;
  best.distance_m = std::numeric_limits<double>::infinity();

  // Intersection: an edge of one triangle crossing the other. Impossible when either
  // triangle lies strictly on one side of the other's plane (the common, cheap case).
  const Vector3d nA = (a1 - a0).cross(a2 - a0);
  const Vector3d nB = (b1 - b0).cross(b2 - b0);
  const double sa0 = nB.dot(a0 - b0);
  const double sa1 = nB.dot(a1 - b0);
  const double sa2 = nB.dot(a2 - b0);
  const double sb0 = nA.dot(b0 - a0);
  const double sb1 = nA.dot(b1 - a0);
  const double sb2 = nA.dot(b2 - a0);
  const bool a_one_side = (sa0 > 0.0 && sa1 > 0.0 && sa2 > 0.0) || (sa0 < 0.0 && sa1 < 0.0 && sa2 < 0.0);
  const bool b_one_side = (sb0 > 0.0 && sb1 > 0.0 && sb2 > 0.0) || (sb0 < 0.0 && sb1 < 0.0 && sb2 < 0.0);
  for (int k = 0; k < 3 && !a_one_side && !b_one_side; ++k) {
    double s = 0.0;
    if (segmentTriangleCrossing(*A[k], *A[(k + 1) % 3], b0, b1, b2, s)) {
      const Vector3d x = *A[k] + s * (*A[(k + 1) % 3] - *A[k]);
      const PointTriangleResult on_b = closestPointTriangle(x, b0, b1, b2);
      best.p = x;
      best.q = on_b.point;
      best.distance_m = 0.0;
      best.feature_a = edgeFeature(k, s);
      best.feature_b = on_b.feature;
      best.intersecting = true;
      return best;
    }
  }
  for (int k = 0; k < 3 && !a_one_side && !b_one_side; ++k) {
    double s = 0.0;
    if (segmentTriangleCrossing(*B[k], *B[(k + 1) % 3], a0, a1, a2, s)) {
      const Vector3d x = *B[k] + s * (*B[(k + 1) % 3] - *B[k]);
      const PointTriangleResult on_a = closestPointTriangle(x, a0, a1, a2);
      best.p = on_a.point;
      best.q = x;
      best.distance_m = 0.0;
      best.feature_a = on_a.feature;
      best.feature_b = edgeFeature(k, s);
      best.intersecting = true;
      return best;
    }
  }

  // Disjoint: vertex-face candidates, then edge-edge candidates.
  bool best_is_vertex_of_a = true;
  for (int k = 0; k < 3; ++k) {
    const PointTriangleResult r = closestPointTriangle(*A[k], b0, b1, b2);
    if (r.distance_m < best.distance_m) {
      best.p = *A[k];
      best.q = r.point;
      best.distance_m = r.distance_m;
      best.feature_a = {Kind::kVertex, static_cast<std::uint8_t>(k)};
      best.feature_b = r.feature;
    }
  }
  for (int k = 0; k < 3; ++k) {
    const PointTriangleResult r = closestPointTriangle(*B[k], a0, a1, a2);
    if (r.distance_m < best.distance_m) {
      best_is_vertex_of_a = false;
      best.p = r.point;
      best.q = *B[k];
      best.distance_m = r.distance_m;
      best.feature_a = r.feature;
      best.feature_b = {Kind::kVertex, static_cast<std::uint8_t>(k)};
    }
  }
  // Early exit: the distance is convex over the pair of triangles, so the best vertex
  // candidate is the minimum when each of its points is also the other triangle's closest
  // point to the other (one side holds by construction; test the other exactly).
  if (best.distance_m > 0.0) {
    const double d2 = best.distance_m * best.distance_m;
    const double other = best_is_vertex_of_a ? squaredDistancePointTriangle(best.q, a0, a1, a2)
                                             : squaredDistancePointTriangle(best.p, b0, b1, b2);
    if (other >= d2) return best;
  }
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const SegmentSegmentResult r = closestPointsSegmentSegment(*A[i], *A[(i + 1) % 3], *B[j], *B[(j + 1) % 3]);
      if (r.distance_m < best.distance_m) {
        best.p = r.p;
        best.q = r.q;
        best.distance_m = r.distance_m;
        best.feature_a = edgeFeature(i, r.s);
        best.feature_b = edgeFeature(j, r.t);
      }
    }
  }
  return best;
}

}  // namespace fullarm::haptics
