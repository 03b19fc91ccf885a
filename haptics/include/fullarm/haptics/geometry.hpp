#pragma once
/// @file
/// Exact closest points between triangles, segments and points, with the closest feature of
/// each triangle. All functions are real-time safe (@rt): no allocation, bounded time.

#include <Eigen/Core>
#include <cstdint>

namespace fullarm::haptics {

/// Closest feature of one triangle (a, b, c) in local numbering: vertex k (0..2), edge k
/// joining vertex k and vertex (k+1)%3, or the face interior.
struct LocalFeature {
  enum class Kind : std::uint8_t { kVertex, kEdge, kFace };
  Kind kind = Kind::kFace;
  std::uint8_t index = 0;  ///< vertex or edge number 0..2 (0 for the face)
};

/// Closest point of a triangle to a point.
struct PointTriangleResult {
  Eigen::Vector3d point;  ///< closest point on the triangle [m]
  LocalFeature feature;   ///< feature whose relative interior holds the point
  double distance_m = 0.0;
};

/// Closest point on triangle (a, b, c) to p (Voronoi-region method, Ericson, "Real-Time
/// Collision Detection" section 5.1.5). A degenerate triangle is not allowed.
/// @rt
[[nodiscard]] PointTriangleResult closestPointTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                       const Eigen::Vector3d& b, const Eigen::Vector3d& c) noexcept;

/// Squared distance from p to triangle (a, b, c) [m^2] (same regions as closestPointTriangle,
/// no square root, no feature): the cheap screening test of local descent and SNCH acceptance.
/// @rt
[[nodiscard]] double squaredDistancePointTriangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                                  const Eigen::Vector3d& b, const Eigen::Vector3d& c) noexcept;

/// Closest points of segments [p0,p1] and [q0,q1]: parameters s, t in [0, 1] with the points
/// p0 + s (p1 - p0) and q0 + t (q1 - q0). Parallel segments give one of the closest pairs.
struct SegmentSegmentResult {
  double s = 0.0;
  double t = 0.0;
  Eigen::Vector3d p;
  Eigen::Vector3d q;
  double distance_m = 0.0;
};

/// @rt
[[nodiscard]] SegmentSegmentResult closestPointsSegmentSegment(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                               const Eigen::Vector3d& q0,
                                                               const Eigen::Vector3d& q1) noexcept;

/// Closest points of two triangles A = (a0, a1, a2) and B = (b0, b1, b2).
struct TriangleTriangleResult {
  Eigen::Vector3d p;  ///< closest point on A [m]
  Eigen::Vector3d q;  ///< closest point on B [m]
  double distance_m = 0.0;
  LocalFeature feature_a;
  LocalFeature feature_b;
  bool intersecting = false;  ///< the triangles intersect (p == q, distance 0)
};

/// Exact closest points of two triangles with the closest feature of each. For disjoint
/// triangles the minimum is attained by a vertex-face or an edge-edge pair, so the 6
/// vertex-triangle and 9 edge-edge candidates are compared (the first strictly smallest in
/// that order wins, which makes parallel configurations deterministic). Intersecting triangles
/// (an edge of one crossing the other) report distance 0 at a crossing point, classified as
/// the crossing edge on one side and the crossed triangle's feature on the other.
/// @rt
[[nodiscard]] TriangleTriangleResult closestPointsTriangleTriangle(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                                                   const Eigen::Vector3d& a2, const Eigen::Vector3d& b0,
                                                                   const Eigen::Vector3d& b1,
                                                                   const Eigen::Vector3d& b2) noexcept;

/// A triangle with the edge vectors that the closest-point routines reuse: prepare it once,
/// then query it against many points or triangles (local descent evaluates one triangle
/// against each neighbour of the other side). Vertices are copied, so the source may change.
struct PreparedTriangle {
  Eigen::Vector3d v[3];     ///< vertices a, b, c [m]
  Eigen::Vector3d edge[3];  ///< edge k = v[(k+1)%3] - v[k]
  Eigen::Vector3d ac;       ///< c - a (= -edge[2])
  Eigen::Vector3d normal;   ///< (b - a) x (c - a), not normalised
  double normal_sq;         ///< |normal|^2
  double edge_sq[3];        ///< |edge k|^2
};

/// @rt
[[nodiscard]] inline PreparedTriangle prepareTriangle(const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                                      const Eigen::Vector3d& c) noexcept {
  PreparedTriangle t;
  t.v[0] = a;
  t.v[1] = b;
  t.v[2] = c;
  t.edge[0] = b - a;
  t.edge[1] = c - b;
  t.edge[2] = a - c;
  t.ac = c - a;
  t.normal = t.edge[0].cross(t.ac);
  t.normal_sq = t.normal.squaredNorm();
  for (int k = 0; k < 3; ++k) t.edge_sq[k] = t.edge[k].squaredNorm();
  return t;
}

/// Closest points of a segment and a triangle (see closestPointsSpanningSegmentTriangle).
struct SegmentTriangleResult {
  double s = 0.0;            ///< parameter of p on the segment, in [0, 1]
  Eigen::Vector3d p;         ///< closest point on the segment [m]
  Eigen::Vector3d q;         ///< closest point on the triangle [m]
  double distance_sq = 0.0;  ///< |p - q|^2 [m^2]
  /// Closest feature of the triangle (the face only from closestPointsSegmentTriangle).
  LocalFeature feature_t;
};

/// Exact closest points of the segment [p0, p1] and triangle t, with t's closest feature and the
/// segment parameter s of p (Ericson, "Real-Time Collision Detection" 5.1.10). A segment
/// crossing t gives distance 0 at the crossing point (t's feature there, the face inside).
/// Otherwise the minimum of a segment and a triangle is attained by an end of the segment
/// against the triangle or by the segment against one of its edges: the five candidates are
/// compared in that order (p0, p1, edges 0, 1, 2), the first strictly smallest wins, so
/// parallel configurations are deterministic. A candidate whose lower bound (its distance to
/// the triangle's plane, or the distance of the segment's end nearer to that plane when both
/// lie on one side) exceeds the best so far is skipped. A segment of zero length is a point.
/// The distance of a capsule (radius r around the segment) to the triangle is
/// max(0, sqrt(distance_sq) - r).
/// @rt
[[nodiscard]] SegmentTriangleResult closestPointsSegmentTriangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                                 const PreparedTriangle& t) noexcept;

/// Parameter s in [0, 1] of the point p0 + s (p1 - p0) of the segment [p0, p1] closest to x (0
/// for a segment of zero length).
/// @rt
[[nodiscard]] inline double closestSegmentParameter(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1,
                                                    const Eigen::Vector3d& x) noexcept {
  const Eigen::Vector3d d = p1 - p0;
  const double d_sq = d.squaredNorm();
  if (!(d_sq > 0.0)) return 0.0;
  const double s = (x - p0).dot(d) / d_sq;
  return s <= 0.0 ? 0.0 : (s >= 1.0 ? 1.0 : s);
}

/// Exact closest points of the segment [p0, p0 + d] and triangle t when the segment spans the
/// triangle along its direction (every vertex of t projects onto the segment: 0 <= (v - p0) . d
/// <= |d|^2), the dominant case of local descent, where a link capsule's long strip edge lies
/// over a small triangle of the environment. Then the closest point of the segment to any point
/// of t is that of the infinite line, and the distance is that of the line to t: the distance
/// from the line's point to t projected along d onto the plane perpendicular to d, one
/// point-triangle query (Ericson 5.1.5) instead of the three edge-edge and two endpoint-triangle
/// candidates of the general segment-triangle query. Returns false, and leaves `out`
/// unspecified, when the kernel does not apply: a vertex projects outside the segment, the
/// projected triangle holds the line (the segment meets t: the face region) or is degenerate
/// beyond the region tests. The caller then runs the general query.
/// @param d segment direction (p1 - p0) [m], d_sq = |d|^2 > 0 [m^2]
/// @rt
[[nodiscard]] bool closestPointsSpanningSegmentTriangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& d,
                                                        double d_sq, const PreparedTriangle& t,
                                                        SegmentTriangleResult& out) noexcept;

/// Same on the raw vertices t0, t1, t2 of the triangle (nothing prepared).
/// @rt
[[nodiscard]] bool closestPointsSpanningSegmentTriangle(const Eigen::Vector3d& p0, const Eigen::Vector3d& d,
                                                        double d_sq, const Eigen::Vector3d& t0,
                                                        const Eigen::Vector3d& t1, const Eigen::Vector3d& t2,
                                                        SegmentTriangleResult& out) noexcept;

/// Optimality certificate of an edge-edge pair (the KKT conditions of the triangle-triangle
/// distance at the pair), on raw vertices: no triangle is prepared. Edge a0 -> a1 of triangle
/// A and edge b0 -> b1 of triangle B, with `inward_a` / `inward_b` any positive multiple of the
/// direction into the triangle perpendicular to the edge in its plane (n x e for a triangle
/// wound counter-clockwise about n). Returns true, with the closest points p (on A), q (on B)
/// and |p - q|^2, when the closest points of the two lines lie strictly inside both edges, the
/// distance is positive and the offset q - p points into neither triangle (with the slack of
/// closestPointsTriangleTriangleWarm): then (p, q) is the closest pair of the two triangles.
/// Otherwise false (parallel edges, an end reached, an offset into a triangle): the caller
/// computes the pair. The test of closestPointsTriangleTriangleWarm's edge-edge guess.
/// @rt
[[nodiscard]] bool certifyEdgeEdgePair(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1,
                                       const Eigen::Vector3d& inward_a, const Eigen::Vector3d& b0,
                                       const Eigen::Vector3d& b1, const Eigen::Vector3d& inward_b, Eigen::Vector3d& p,
                                       Eigen::Vector3d& q, double& distance_sq) noexcept;

/// Optimality certificate of a vertex against a prepared triangle: vertex v of a triangle whose
/// two edges leaving v are `to_next` and `to_prev`, against triangle t. Returns true, with t's
/// closest point q, its feature and |v - q|^2 > 0, when v is also its own triangle's closest
/// point to q (the offset q - v has no positive component along either edge leaving v): the
/// pair is then the closest pair of the two triangles. The test of
/// closestPointsTriangleTriangleWarm's vertex guess, without preparing v's triangle.
/// @rt
[[nodiscard]] bool certifyVertexTriangle(const Eigen::Vector3d& v, const Eigen::Vector3d& to_next,
                                         const Eigen::Vector3d& to_prev, const PreparedTriangle& t, Eigen::Vector3d& q,
                                         double& distance_sq, LocalFeature& feature_t) noexcept;

/// Same as squaredDistancePointTriangle on a prepared triangle.
/// @rt
[[nodiscard]] double squaredDistancePointTriangle(const Eigen::Vector3d& p, const PreparedTriangle& t) noexcept;

/// Same as closestPointTriangle on a prepared triangle.
/// @rt
[[nodiscard]] PointTriangleResult closestPointTriangle(const Eigen::Vector3d& p, const PreparedTriangle& t) noexcept;

/// Same result as closestPointsTriangleTriangle(a0, ..., b2) on prepared triangles (the same
/// candidates in the same order; squared distances are compared, one square root at the end).
/// @rt
[[nodiscard]] TriangleTriangleResult closestPointsTriangleTriangle(const PreparedTriangle& A,
                                                                   const PreparedTriangle& B) noexcept;

/// Closest points warm-started from a guess of the closest feature pair (for example the pair
/// of the previous tick; a face guess also stands for "unknown"). The candidate of the guess is
/// computed alone, in this order: a vertex guess gives the vertex against the other triangle;
/// an edge-edge guess the two edges; an edge against a face guess the edge against the whole
/// other triangle (unless it crosses it); two face guesses the vertex of either triangle
/// nearest to the other's plane. It is returned when it passes the exact optimality test of two convex sets: p is the
/// point of A closest to q and q the point of B closest to p (tested on the Voronoi region of
/// the feature: two dot products for a vertex, one per side for an edge interior). Otherwise
/// the full closestPointsTriangleTriangle runs. The distance always equals the cold
/// computation's (to rounding); in degenerate configurations with several closest pairs
/// (parallel edges or faces) the representative may differ.
/// @rt
[[nodiscard]] TriangleTriangleResult closestPointsTriangleTriangleWarm(const PreparedTriangle& A,
                                                                       const PreparedTriangle& B,
                                                                       const LocalFeature& guess_a,
                                                                       const LocalFeature& guess_b) noexcept;

/// The warm start of edge k of E against a triangle given by its raw vertices (nothing
/// prepared), whose closest feature is unknown, through the spanning-segment kernel: the
/// result of closestPointsTriangleTriangleWarm(E, prepareTriangle(t0, t1, t2), edge k, face),
/// bit for bit, when the kernel applies and its pair passes the optimality test; false
/// otherwise (then that warm start, on the prepared triangle, decides). Local descent's
/// evaluation of an object triangle against the link edge that holds the closest point.
/// @rt
[[nodiscard]] bool closestPointsEdgeTriangleSpanning(const PreparedTriangle& E, int k, const Eigen::Vector3d& t0,
                                                     const Eigen::Vector3d& t1, const Eigen::Vector3d& t2,
                                                     TriangleTriangleResult& out) noexcept;

}  // namespace fullarm::haptics
