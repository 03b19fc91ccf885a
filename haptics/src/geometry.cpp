#include "fullarm/haptics/geometry.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

namespace fullarm::haptics {

using Eigen::Vector3d;
using Kind = LocalFeature::Kind;

// G1: closest points by Voronoi regions (reports/equations.md).
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

// G1: closest points by Voronoi regions (reports/equations.md).
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

namespace {

// Closest points of two segments p0 + s d1 and q0 + t d2 (s, t in [0, 1]) with the directions and their
// squared lengths a, e given: Ericson 5.1.9 with clamping; the parallel case picks s = 0 then clamps.
struct SquaredSegmentResult {
  double s;
  double t;
  Vector3d p;
  Vector3d q;
  double distance_sq;
};

inline SquaredSegmentResult closestSegmentSegmentSquared(const Vector3d& p0, const Vector3d& d1, double a,
                                                         const Vector3d& q0, const Vector3d& d2, double e) noexcept {
  const Vector3d r = p0 - q0;
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
  SquaredSegmentResult out{s, t, p0 + s * d1, q0 + t * d2, 0.0};
  out.distance_sq = (out.p - out.q).squaredNorm();
  return out;
}

}  // namespace

// G1: closest points by Voronoi regions (reports/equations.md).
SegmentSegmentResult closestPointsSegmentSegment(const Vector3d& p0, const Vector3d& p1, const Vector3d& q0,
                                                 const Vector3d& q1) noexcept {
  const Vector3d d1 = p1 - p0;
  const Vector3d d2 = q1 - q0;
  const SquaredSegmentResult r = closestSegmentSegmentSquared(p0, d1, d1.squaredNorm(), q0, d2, d2.squaredNorm());
  SegmentSegmentResult out;
  out.s = r.s;
  out.t = r.t;
  out.p = r.p;
  out.q = r.q;
  out.distance_m = std::sqrt(r.distance_sq);
  return out;
}

namespace {

LocalFeature edgeFeature(int k, double s) noexcept {
  if (s <= 0.0) return {Kind::kVertex, static_cast<std::uint8_t>(k)};
  if (s >= 1.0) return {Kind::kVertex, static_cast<std::uint8_t>((k + 1) % 3)};
  return {Kind::kEdge, static_cast<std::uint8_t>(k)};
}

}  // namespace

// G2: triangle-triangle distance (reports/equations.md).
TriangleTriangleResult closestPointsTriangleTriangle(const Vector3d& a0, const Vector3d& a1, const Vector3d& a2,
                                                     const Vector3d& b0, const Vector3d& b1,
                                                     const Vector3d& b2) noexcept {
  return closestPointsTriangleTriangle(prepareTriangle(a0, a1, a2), prepareTriangle(b0, b1, b2));
}

// ---------------------------------------------------------------------------------------------
// Prepared triangles: the arithmetic of closestPointTriangle and closestPointsSegmentSegment,
// with the edge vectors computed once per triangle, squared distances compared and one square
// root per triangle pair.

namespace {

// Closest point of a prepared triangle to p with its squared distance and feature (Ericson
// 5.1.5, the same region tests as closestPointTriangle).
struct SquaredPointResult {
  Vector3d point;
  double distance_sq;
  LocalFeature feature;
};

inline SquaredPointResult closestPointSquared(const Vector3d& p, const PreparedTriangle& t) noexcept {
  const Vector3d& a = t.v[0];
  const Vector3d& ab = t.edge[0];
  const Vector3d& ac = t.ac;
  const Vector3d ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0.0 && d2 <= 0.0) return {a, ap.squaredNorm(), {Kind::kVertex, 0}};
  const Vector3d bp = p - t.v[1];
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0.0 && d4 <= d3) return {t.v[1], bp.squaredNorm(), {Kind::kVertex, 1}};
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    const Vector3d x = a + (d1 / (d1 - d3)) * ab;
    return {x, (p - x).squaredNorm(), {Kind::kEdge, 0}};
  }
  const Vector3d cp = p - t.v[2];
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0.0 && d5 <= d6) return {t.v[2], cp.squaredNorm(), {Kind::kVertex, 2}};
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    const Vector3d x = a + (d2 / (d2 - d6)) * ac;
    return {x, (p - x).squaredNorm(), {Kind::kEdge, 2}};
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
    const Vector3d x = t.v[1] + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * t.edge[1];
    return {x, (p - x).squaredNorm(), {Kind::kEdge, 1}};
  }
  const double denom = 1.0 / (va + vb + vc);
  const Vector3d x = a + ab * (vb * denom) + ac * (vc * denom);
  return {x, (p - x).squaredNorm(), {Kind::kFace, 0}};
}

// segmentTriangleCrossing against a prepared triangle (same arithmetic).
bool segmentCrossesPrepared(const Vector3d& p0, const Vector3d& p1, const PreparedTriangle& t, double& s_out) noexcept {
  const Vector3d& n = t.normal;
  const double h0 = n.dot(p0 - t.v[0]);
  const double h1 = n.dot(p1 - t.v[0]);
  if ((h0 > 0.0 && h1 > 0.0) || (h0 < 0.0 && h1 < 0.0) || h0 == h1) return false;
  const double s = h0 / (h0 - h1);
  const Vector3d x = p0 + s * (p1 - p0);
  for (int k = 0; k < 3; ++k) {
    if (n.dot(t.edge[k].cross(x - t.v[k])) < 0.0) return false;
  }
  s_out = s;
  return true;
}

// Relative slack of the plane-distance bounds that skip candidates (rounding of the bound).
constexpr double kBoundSlack = 1e-12;

// Relative slack of the warm-start optimality tests: a cosine this small counts as
// perpendicular (parallel edges and faces keep their feature pair instead of flickering
// between equally close representatives); the distance it can hide is ~1e-24 relative.
constexpr double kWarmCosineSlackSq = 1e-24;

// w . e <= 0 with the slack above.
inline bool notTowards(const Vector3d& w, const Vector3d& e) noexcept {
  const double dot = w.dot(e);
  return dot <= 0.0 || dot * dot <= kWarmCosineSlackSq * w.squaredNorm() * e.squaredNorm();
}

// Is vertex k of t the closest point of t to the point at offset w from it?
inline bool vertexRegionHolds(const PreparedTriangle& t, int k, const Vector3d& w) noexcept {
  // Ericson's vertex region: w . (v[k+1] - v[k]) <= 0 and w . (v[k+2] - v[k]) <= 0.
  return notTowards(w, t.edge[k]) && notTowards(w, -t.edge[(k + 2) % 3]);
}

// Is the interior point of edge k of t at offset w (perpendicular to the edge) from the
// target's closest point? Then w must not point into the triangle.
inline bool edgeRegionHolds(const PreparedTriangle& t, int k, const Vector3d& w) noexcept {
  return notTowards(w, t.normal.cross(t.edge[k]));
}

}  // namespace

double squaredDistancePointTriangle(const Vector3d& p, const PreparedTriangle& t) noexcept {
  return closestPointSquared(p, t).distance_sq;
}

// G8: segment-triangle closest points, Ericson 5.1.10 (reports/equations.md).
SegmentTriangleResult closestPointsSegmentTriangle(const Vector3d& p0, const Vector3d& p1,
                                                   const PreparedTriangle& t) noexcept {
  SegmentTriangleResult best;
  const Vector3d d = p1 - p0;
  const double d_sq = d.squaredNorm();
  // Heights of the ends over the plane (times |n|).
  const double h0 = t.normal.dot(p0 - t.v[0]);
  const double h1 = t.normal.dot(p1 - t.v[0]);
  if (d_sq > 0.0) {
    double s = 0.0;
    if (segmentCrossesPrepared(p0, p1, t, s)) {
      const Vector3d x = p0 + s * d;
      best.s = s;
      best.p = x;
      best.q = x;
      best.distance_sq = 0.0;
      best.feature_t = closestPointSquared(x, t).feature;
      return best;
    }
  }
  const double inv_n = t.normal_sq > 0.0 ? 1.0 / t.normal_sq : 0.0;  // 0: no bound
  double best_sq = std::numeric_limits<double>::infinity();
  const auto beyond = [&best_sq](double lower_bound_sq) noexcept {
    return lower_bound_sq > best_sq * (1.0 + kBoundSlack);
  };
  const auto endpoint = [&](const Vector3d& x, double s, double h) noexcept {
    if (beyond(h * h * inv_n)) return;
    const SquaredPointResult r = closestPointSquared(x, t);
    if (r.distance_sq < best_sq) {
      best_sq = r.distance_sq;
      best.s = s;
      best.p = x;
      best.q = r.point;
      best.feature_t = r.feature;
    }
  };
  endpoint(p0, 0.0, h0);
  if (!(d_sq > 0.0)) {
    best.distance_sq = best_sq;
    return best;
  }
  endpoint(p1, 1.0, h1);
  // The segment against the edges: below both the segment's plane bound (its end nearer to the
  // plane, both ends on one side; not crossing) and each edge lies in the plane.
  const double h_min = (h0 > 0.0) == (h1 > 0.0) && h0 != 0.0 && h1 != 0.0 ? std::min(std::abs(h0), std::abs(h1)) : 0.0;
  if (beyond(h_min * h_min * inv_n)) {
    best.distance_sq = best_sq;
    return best;
  }
  for (int j = 0; j < 3; ++j) {
    const SquaredSegmentResult r = closestSegmentSegmentSquared(p0, d, d_sq, t.v[j], t.edge[j], t.edge_sq[j]);
    if (r.distance_sq < best_sq) {
      best_sq = r.distance_sq;
      best.s = r.s;
      best.p = r.p;
      best.q = r.q;
      best.feature_t = edgeFeature(j, r.t);
    }
  }
  best.distance_sq = best_sq;
  return best;
}

PointTriangleResult closestPointTriangle(const Vector3d& p, const PreparedTriangle& t) noexcept {
  const SquaredPointResult r = closestPointSquared(p, t);
  PointTriangleResult out;
  out.point = r.point;
  out.feature = r.feature;
  out.distance_m = std::sqrt(r.distance_sq);
  return out;
}

TriangleTriangleResult closestPointsTriangleTriangle(const PreparedTriangle& A, const PreparedTriangle& B) noexcept {
  TriangleTriangleResult best;
  // Intersection: an edge of one triangle crossing the other; impossible when either lies
  // strictly on one side of the other's plane.
  const double sa0 = B.normal.dot(A.v[0] - B.v[0]);
  const double sa1 = B.normal.dot(A.v[1] - B.v[0]);
  const double sa2 = B.normal.dot(A.v[2] - B.v[0]);
  const double sb0 = A.normal.dot(B.v[0] - A.v[0]);
  const double sb1 = A.normal.dot(B.v[1] - A.v[0]);
  const double sb2 = A.normal.dot(B.v[2] - A.v[0]);
  const bool a_one_side = (sa0 > 0.0 && sa1 > 0.0 && sa2 > 0.0) || (sa0 < 0.0 && sa1 < 0.0 && sa2 < 0.0);
  const bool b_one_side = (sb0 > 0.0 && sb1 > 0.0 && sb2 > 0.0) || (sb0 < 0.0 && sb1 < 0.0 && sb2 < 0.0);
  if (!a_one_side && !b_one_side) {
    for (int k = 0; k < 3; ++k) {
      double s = 0.0;
      if (segmentCrossesPrepared(A.v[k], A.v[(k + 1) % 3], B, s)) {
        const Vector3d x = A.v[k] + s * (A.v[(k + 1) % 3] - A.v[k]);
        const SquaredPointResult on_b = closestPointSquared(x, B);
        best.p = x;
        best.q = on_b.point;
        best.distance_m = 0.0;
        best.feature_a = edgeFeature(k, s);
        best.feature_b = on_b.feature;
        best.intersecting = true;
        return best;
      }
    }
    for (int k = 0; k < 3; ++k) {
      double s = 0.0;
      if (segmentCrossesPrepared(B.v[k], B.v[(k + 1) % 3], A, s)) {
        const Vector3d x = B.v[k] + s * (B.v[(k + 1) % 3] - B.v[k]);
        const SquaredPointResult on_a = closestPointSquared(x, A);
        best.p = on_a.point;
        best.q = x;
        best.distance_m = 0.0;
        best.feature_a = on_a.feature;
        best.feature_b = edgeFeature(k, s);
        best.intersecting = true;
        return best;
      }
    }
  }

  // Disjoint: vertex-face candidates, then edge-edge candidates. A candidate whose distance
  // to the other triangle's plane (a lower bound) already exceeds the best is skipped; the
  // slack keeps rounding-level ties computed, so the first strictly smallest still wins.
  const std::array<double, 3> sa{sa0, sa1, sa2};
  const std::array<double, 3> sb{sb0, sb1, sb2};
  const double inv_nb = B.normal_sq > 0.0 ? 1.0 / B.normal_sq : 0.0;  // 0: no bound
  const double inv_na = A.normal_sq > 0.0 ? 1.0 / A.normal_sq : 0.0;
  double best_sq = std::numeric_limits<double>::infinity();
  auto beyond = [&best_sq](double lower_bound_sq) noexcept { return lower_bound_sq > best_sq * (1.0 + kBoundSlack); };
  bool best_is_vertex_of_a = true;
  for (int k = 0; k < 3; ++k) {
    if (beyond(sa[k] * sa[k] * inv_nb)) continue;
    const SquaredPointResult r = closestPointSquared(A.v[k], B);
    if (r.distance_sq < best_sq) {
      best.p = A.v[k];
      best.q = r.point;
      best_sq = r.distance_sq;
      best.feature_a = {Kind::kVertex, static_cast<std::uint8_t>(k)};
      best.feature_b = r.feature;
    }
  }
  for (int k = 0; k < 3; ++k) {
    if (beyond(sb[k] * sb[k] * inv_na)) continue;
    const SquaredPointResult r = closestPointSquared(B.v[k], A);
    if (r.distance_sq < best_sq) {
      best_is_vertex_of_a = false;
      best.p = r.point;
      best.q = B.v[k];
      best_sq = r.distance_sq;
      best.feature_a = r.feature;
      best.feature_b = {Kind::kVertex, static_cast<std::uint8_t>(k)};
    }
  }
  // Early exit (convexity): the best vertex candidate is the minimum when its vertex is also
  // the closest point of its own triangle to the other point. Decided by the vertex's region
  // (signs of dot products), not by comparing squared distances: with nearly parallel edges the
  // closest point can sit 1e-9 m along an edge from the vertex while the squared distances agree
  // to the last bit, and the true minimum lies far along the edges, nanometres closer.
  if (best_sq > 0.0) {
    const bool mutual = best_is_vertex_of_a ? vertexRegionHolds(A, best.feature_a.index, best.q - best.p)
                                            : vertexRegionHolds(B, best.feature_b.index, best.p - best.q);
    if (mutual) {
      best.distance_m = std::sqrt(best_sq);
      return best;
    }
  }
  // Plane-distance bound of each edge: its nearer endpoint when both lie on one side.
  auto edgeBound = [](const std::array<double, 3>& s, int i, double inv) noexcept {
    const double s0 = s[static_cast<std::size_t>(i)];
    const double s1 = s[static_cast<std::size_t>((i + 1) % 3)];
    if ((s0 > 0.0) != (s1 > 0.0) || s0 == 0.0 || s1 == 0.0) return 0.0;
    const double m = std::min(std::abs(s0), std::abs(s1));
    return m * m * inv;
  };
  const std::array<double, 3> bound_a{edgeBound(sa, 0, inv_nb), edgeBound(sa, 1, inv_nb), edgeBound(sa, 2, inv_nb)};
  const std::array<double, 3> bound_b{edgeBound(sb, 0, inv_na), edgeBound(sb, 1, inv_na), edgeBound(sb, 2, inv_na)};
  for (int i = 0; i < 3; ++i) {
    if (beyond(bound_a[static_cast<std::size_t>(i)])) continue;
    for (int j = 0; j < 3; ++j) {
      if (beyond(bound_b[static_cast<std::size_t>(j)])) continue;
      const SquaredSegmentResult r =
          closestSegmentSegmentSquared(A.v[i], A.edge[i], A.edge_sq[i], B.v[j], B.edge[j], B.edge_sq[j]);
      if (r.distance_sq < best_sq) {
        best.p = r.p;
        best.q = r.q;
        best_sq = r.distance_sq;
        best.feature_a = edgeFeature(i, r.s);
        best.feature_b = edgeFeature(j, r.t);
      }
    }
  }
  best.distance_m = std::sqrt(best_sq);
  return best;
}

namespace {

// Vertex of `t` nearest to the plane of `face` when t lies strictly on one side of it, else -1.
int vertexNearestPlane(const PreparedTriangle& t, const PreparedTriangle& face) noexcept {
  const double s0 = face.normal.dot(t.v[0] - face.v[0]);
  const double s1 = face.normal.dot(t.v[1] - face.v[0]);
  const double s2 = face.normal.dot(t.v[2] - face.v[0]);
  if (s0 > 0.0 && s1 > 0.0 && s2 > 0.0) return s0 <= s1 ? (s0 <= s2 ? 0 : 2) : (s1 <= s2 ? 1 : 2);
  if (s0 < 0.0 && s1 < 0.0 && s2 < 0.0) return s0 >= s1 ? (s0 >= s2 ? 0 : 2) : (s1 >= s2 ? 1 : 2);
  return -1;
}

// Candidate of vertex k of `v_tri` against triangle `other`, kept when the vertex is also the
// closest point of v_tri to the other point (q = closest point of `other` by construction).
bool vertexCandidate(const PreparedTriangle& v_tri, int k, const PreparedTriangle& other, Vector3d& vertex_point,
                     Vector3d& other_point, double& distance_sq, LocalFeature& other_feature) noexcept {
  const SquaredPointResult c = closestPointSquared(v_tri.v[k], other);
  if (!(c.distance_sq > 0.0) || !vertexRegionHolds(v_tri, k, c.point - v_tri.v[k])) return false;
  vertex_point = v_tri.v[k];
  other_point = c.point;
  distance_sq = c.distance_sq;
  other_feature = c.feature;
  return true;
}

}  // namespace

// G4: optimality certificate of a closest pair (reports/equations.md).
bool certifyVertexTriangle(const Vector3d& v, const Vector3d& to_next, const Vector3d& to_prev,
                           const PreparedTriangle& t, Vector3d& q, double& distance_sq,
                           LocalFeature& feature_t) noexcept {
  const SquaredPointResult c = closestPointSquared(v, t);
  const Vector3d w = c.point - v;
  if (!(c.distance_sq > 0.0) || !notTowards(w, to_next) || !notTowards(w, to_prev)) return false;
  q = c.point;
  distance_sq = c.distance_sq;
  feature_t = c.feature;
  return true;
}

// G4: optimality certificate of a closest pair (reports/equations.md).
bool certifyEdgeEdgePair(const Vector3d& a0, const Vector3d& a1, const Vector3d& inward_a, const Vector3d& b0,
                         const Vector3d& b1, const Vector3d& inward_b, Vector3d& p, Vector3d& q,
                         double& distance_sq) noexcept {
  // Closest points of the two lines a0 + s da, b0 + t db (Ericson 5.1.8): the 2x2 normal
  // equations, solved only when the solution is interior to both segments (0 < s, t < 1, tested
  // on the numerators against the positive denominator, no division before).
  const Vector3d da = a1 - a0;
  const Vector3d db = b1 - b0;
  const Vector3d r = a0 - b0;
  const double a = da.squaredNorm();
  const double e = db.squaredNorm();
  const double b = da.dot(db);
  const double c = da.dot(r);
  const double f = db.dot(r);
  const double denom = a * e - b * b;
  if (!(denom > 1e-20 * a * e)) return false;  // parallel (the threshold of the general routine)
  const double s_num = b * f - c * e;
  const double t_num = a * f - b * c;
  if (!(s_num > 0.0 && s_num < denom && t_num > 0.0 && t_num < denom)) return false;
  const double inv = 1.0 / denom;
  p = a0 + (s_num * inv) * da;
  q = b0 + (t_num * inv) * db;
  const Vector3d w = q - p;
  distance_sq = w.squaredNorm();
  // Interior points of both edges, the offset perpendicular to both: each point is its
  // triangle's closest point iff the offset does not point into that triangle.
  return distance_sq > 0.0 && notTowards(w, inward_a) && notTowards(-w, inward_b);
}

// G3: segment-triangle distance of a spanning segment (reports/equations.md).
bool closestPointsSpanningSegmentTriangle(const Vector3d& p0, const Vector3d& d, double d_sq, const PreparedTriangle& t,
                                          SegmentTriangleResult& out) noexcept {
  return closestPointsSpanningSegmentTriangle(p0, d, d_sq, t.v[0], t.v[1], t.v[2], out);
}

bool closestPointsSpanningSegmentTriangle(const Vector3d& p0, const Vector3d& d, double d_sq, const Vector3d& t0,
                                          const Vector3d& t1, const Vector3d& t2, SegmentTriangleResult& out) noexcept {
  const Vector3d* const v[3] = {&t0, &t1, &t2};
  if (!(d_sq > 0.0)) return false;
  const double inv_d_sq = 1.0 / d_sq;
  // Line parameter s_k of each vertex and its offset x_k from the line: the triangle projected
  // along d onto the plane through p0 perpendicular to d, where the line is the origin.
  double s[3];
  Vector3d x[3];
  for (int k = 0; k < 3; ++k) {
    const Vector3d r = *v[k] - p0;
    s[k] = r.dot(d) * inv_d_sq;
    if (!(s[k] >= 0.0 && s[k] <= 1.0)) return false;  // the segment does not span the triangle
    x[k] = r - s[k] * d;
  }
  // Closest point of the projected triangle to the origin (Ericson 5.1.5, the regions of
  // closestPointTriangle with p = 0). Its preimage on t is t's closest point to the line; the
  // segment's point has the same barycentric combination of the s_k. An edge region needs a
  // projected edge of positive length (an edge parallel to d projects to a point: its region
  // test is meaningless, the general query decides).
  const Vector3d ab = x[1] - x[0];
  const Vector3d ac = x[2] - x[0];
  const double d1 = -ab.dot(x[0]);
  const double d2 = -ac.dot(x[0]);
  auto vertex = [&](int k) noexcept {
    out.s = s[k];
    out.q = *v[k];
    out.feature_t = {LocalFeature::Kind::kVertex, static_cast<std::uint8_t>(k)};
  };
  auto edge = [&](int k, double lambda) noexcept {
    const int k1 = (k + 1) % 3;
    if (lambda <= 0.0) return vertex(k);  // an end of the edge (the general query's edgeFeature)
    if (lambda >= 1.0) return vertex(k1);
    out.s = std::clamp(s[k] + lambda * (s[k1] - s[k]), 0.0, 1.0);
    out.q = *v[k] + lambda * (*v[k1] - *v[k]);
    out.feature_t = {LocalFeature::Kind::kEdge, static_cast<std::uint8_t>(k)};
  };
  if (d1 <= 0.0 && d2 <= 0.0) {
    vertex(0);
  } else {
    const double d3 = -ab.dot(x[1]);
    const double d4 = -ac.dot(x[1]);
    const double vc = d1 * d4 - d3 * d2;
    if (d3 >= 0.0 && d4 <= d3) {
      vertex(1);
    } else if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
      if (!(d1 - d3 > 0.0)) return false;
      edge(0, d1 / (d1 - d3));
    } else {
      const double d5 = -ab.dot(x[2]);
      const double d6 = -ac.dot(x[2]);
      const double vb = d5 * d2 - d1 * d6;
      const double va = d3 * d6 - d5 * d4;
      if (d6 >= 0.0 && d5 <= d6) {
        vertex(2);
      } else if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
        // Edge 2 runs from vertex 2 to vertex 0: the point a + w ac is at 1 - w along it.
        if (!(d2 - d6 > 0.0)) return false;
        edge(2, 1.0 - d2 / (d2 - d6));
      } else if (va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0) {
        const double den = (d4 - d3) + (d5 - d6);
        if (!(den > 0.0)) return false;
        edge(1, (d4 - d3) / den);
      } else {
        return false;  // face region: the line meets the triangle inside the segment
      }
    }
  }
  out.p = p0 + out.s * d;
  out.distance_sq = (out.q - out.p).squaredNorm();
  return true;
}

namespace {

// Closest pair of edge k of E and a triangle T that it does not cross: the segment against
// T's three edges, then its endpoints against T (the general segment-triangle query).
void generalEdgeTriangle(const PreparedTriangle& E, int k, const PreparedTriangle& T, Vector3d& e_point,
                         Vector3d& t_point, double& best, LocalFeature& e_feature, LocalFeature& t_feature) noexcept {
  const int k1 = (k + 1) % 3;
  for (int j = 0; j < 3; ++j) {
    const SquaredSegmentResult c =
        closestSegmentSegmentSquared(E.v[k], E.edge[k], E.edge_sq[k], T.v[j], T.edge[j], T.edge_sq[j]);
    if (c.distance_sq < best) {
      best = c.distance_sq;
      e_point = c.p;
      t_point = c.q;
      e_feature = edgeFeature(k, c.s);
      t_feature = edgeFeature(j, c.t);
    }
  }
  // The endpoints against T, unless T's bounding sphere (centre v0, radius its longer edge
  // from v0) puts an endpoint farther than the best edge pair (a long edge against a small
  // triangle: its endpoints are far away).
  const double radius = std::sqrt(std::max(T.edge_sq[0], T.edge_sq[2]));
  for (const int end : {k, k1}) {
    const double centre_distance = (E.v[end] - T.v[0]).norm();
    if (centre_distance > radius) {
      const double lower = centre_distance - radius;
      if (lower * lower > best * (1.0 + kBoundSlack)) continue;
    }
    const SquaredPointResult c = closestPointSquared(E.v[end], T);
    if (c.distance_sq < best) {
      best = c.distance_sq;
      e_point = E.v[end];
      t_point = c.point;
      e_feature = {Kind::kVertex, static_cast<std::uint8_t>(end)};
      t_feature = c.feature;
    }
  }
}

// Closest pair of edge k of E and triangle T (the segment against T: the spanning kernel when
// it applies, else its two endpoints against T and the segment against T's three edges, unless
// it crosses T), kept when the point on E is also E's closest point to the point on T (E's
// Voronoi-region test; the point on T is T's closest point by construction, since the pair
// minimises over the edge and T).
bool edgeCandidate(const PreparedTriangle& E, int k, const PreparedTriangle& T, Vector3d& e_point, Vector3d& t_point,
                   double& distance_sq, LocalFeature& e_feature, LocalFeature& t_feature) noexcept {
  double best = std::numeric_limits<double>::infinity();
  SegmentTriangleResult spanning;
  if (closestPointsSpanningSegmentTriangle(E.v[k], E.edge[k], E.edge_sq[k], T, spanning)) {
    // The dominant case (a long link edge over a small object triangle): one point-triangle
    // query in the plane perpendicular to the edge.
    best = spanning.distance_sq;
    e_point = spanning.p;
    t_point = spanning.q;
    e_feature = edgeFeature(k, spanning.s);
    t_feature = spanning.feature_t;
  } else {
    double s_cross = 0.0;
    if (segmentCrossesPrepared(E.v[k], E.v[(k + 1) % 3], T, s_cross)) return false;
    generalEdgeTriangle(E, k, T, e_point, t_point, best, e_feature, t_feature);
  }
  if (!(best > 0.0)) return false;
  const Vector3d w = t_point - e_point;
  const bool optimal =
      e_feature.kind == Kind::kVertex ? vertexRegionHolds(E, e_feature.index, w) : edgeRegionHolds(E, k, w);
  distance_sq = best;
  return optimal;
}

}  // namespace

// G3: segment-triangle distance of a spanning segment (reports/equations.md).
bool closestPointsEdgeTriangleSpanning(const PreparedTriangle& E, int k, const Vector3d& t0, const Vector3d& t1,
                                       const Vector3d& t2, TriangleTriangleResult& out) noexcept {
  // edgeCandidate's spanning branch and optimality test, step for step.
  SegmentTriangleResult spanning;
  if (!closestPointsSpanningSegmentTriangle(E.v[k], E.edge[k], E.edge_sq[k], t0, t1, t2, spanning) ||
      !(spanning.distance_sq > 0.0)) {
    return false;
  }
  const LocalFeature e_feature = edgeFeature(k, spanning.s);
  const Vector3d w = spanning.q - spanning.p;
  if (!(e_feature.kind == Kind::kVertex ? vertexRegionHolds(E, e_feature.index, w) : edgeRegionHolds(E, k, w))) {
    return false;
  }
  out.p = spanning.p;
  out.q = spanning.q;
  out.distance_m = std::sqrt(spanning.distance_sq);
  out.feature_a = e_feature;
  out.feature_b = spanning.feature_t;
  out.intersecting = false;
  return true;
}

// G4: optimality certificate of a closest pair (reports/equations.md).
TriangleTriangleResult closestPointsTriangleTriangleWarm(const PreparedTriangle& A, const PreparedTriangle& B,
                                                         const LocalFeature& guess_a,
                                                         const LocalFeature& guess_b) noexcept {
  TriangleTriangleResult r;
  double d_sq = 0.0;
  auto vertexOfA = [&](int k) noexcept {
    if (k < 0 || !vertexCandidate(A, k, B, r.p, r.q, d_sq, r.feature_b)) return false;
    r.feature_a = {Kind::kVertex, static_cast<std::uint8_t>(k)};
    return true;
  };
  auto vertexOfB = [&](int k) noexcept {
    if (k < 0 || !vertexCandidate(B, k, A, r.q, r.p, d_sq, r.feature_a)) return false;
    r.feature_b = {Kind::kVertex, static_cast<std::uint8_t>(k)};
    return true;
  };
  bool found = false;
  if (guess_a.kind == Kind::kVertex) {
    found = vertexOfA(guess_a.index);
  } else if (guess_b.kind == Kind::kVertex) {
    found = vertexOfB(guess_b.index);
  } else if (guess_a.kind == Kind::kEdge && guess_b.kind == Kind::kEdge) {
    const int i = guess_a.index;
    const int j = guess_b.index;
    if (certifyEdgeEdgePair(A.v[i], A.v[(i + 1) % 3], A.normal.cross(A.edge[i]), B.v[j], B.v[(j + 1) % 3],
                            B.normal.cross(B.edge[j]), r.p, r.q, d_sq)) {
      r.feature_a = guess_a;
      r.feature_b = guess_b;
      found = true;
    }
  } else if (guess_a.kind == Kind::kEdge) {
    // An edge against an unknown feature: the edge against the whole other triangle.
    found = edgeCandidate(A, guess_a.index, B, r.p, r.q, d_sq, r.feature_a, r.feature_b);
  } else if (guess_b.kind == Kind::kEdge) {
    found = edgeCandidate(B, guess_b.index, A, r.q, r.p, d_sq, r.feature_b, r.feature_a);
  } else {
    // Face guesses: the closest point lies inside a face, so the other side's closest feature
    // is its vertex nearest to that face's plane.
    found = vertexOfB(vertexNearestPlane(B, A)) || vertexOfA(vertexNearestPlane(A, B));
  }
  if (!found) return closestPointsTriangleTriangle(A, B);
  r.distance_m = std::sqrt(d_sq);
  return r;
}

}  // namespace fullarm::haptics
