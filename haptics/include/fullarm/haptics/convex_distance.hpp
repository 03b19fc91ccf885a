#pragma once
/// @file
/// Distance bounds between a triangle and the body of a closed convex mesh (GJK on the
/// Minkowski difference, Gilbert, Johnson & Keerthi 1988), used by the SNCH query to test an
/// object triangle against a whole convex link (the arm's capsules) before descending the link's
/// hierarchy.

#include <Eigen/Geometry>
#include <span>
#include <vector>

#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// Lower and upper bound on a distance [m]: lower_m <= distance <= upper_m.
struct DistanceBounds {
  double lower_m = 0.0;
  double upper_m = 0.0;
  /// Unit axis of the lower bound: axis . (x - y) >= lower_m for every x on the first body and
  /// y on the second (zero when lower_m is 0).
  Eigen::Vector3d axis = Eigen::Vector3d::Zero();
  int iterations = 0;  ///< GJK iterations (support evaluations) used
};

/// The edge graph of a mesh's vertices (compressed rows: the neighbours of vertex v are
/// neighbours[offset[v]] .. neighbours[offset[v + 1] - 1], each once).
struct VertexGraph {
  std::vector<int> offset;
  std::vector<int> neighbours;
};

/// Two capsules (sphere-swept segments) around one segment that bracket the body of a closed
/// convex mesh: the body lies inside the capsule of radius outer_radius_m and holds the one of
/// radius inner_radius_m. For a point c at distance D from the segment, D - outer_radius_m <=
/// dist(c, body) <= D - inner_radius_m, and the direction from the segment's closest point to c
/// separates c from the body by D - outer_radius_m (pointConvexBracketBounds). A few flops
/// instead of a GJK run; on the arm's 16-segment capsules the two radii differ by about 4 %.
struct ConvexBracket {
  Eigen::Vector3d a_m = Eigen::Vector3d::Zero();  ///< segment end, mesh frame [m]
  Eigen::Vector3d b_m = Eigen::Vector3d::Zero();  ///< other end (may equal a_m: two spheres) [m]
  double outer_radius_m = 0.0;                    ///< largest vertex distance to the segment [m]
  /// Smallest depth of the segment's ends behind the face planes [m]; valid() only when > 0
  /// (the segment then lies inside the body with that margin).
  double inner_radius_m = 0.0;
  [[nodiscard]] bool valid() const noexcept { return inner_radius_m > 0.0; }
};

/// The bracket of a closed convex mesh: the segment runs along the principal axis of the
/// vertices (largest eigenvalue of their covariance), shortened at each end by the vertices'
/// largest distance from that axis (for a capsule mesh: its own axis segment); the radii are
/// then computed exactly from the vertices and face planes, so the bracket is rigorous for any
/// segment choice (a poor choice only widens it). Precondition: the mesh is closed and convex.
[[nodiscard]] ConvexBracket buildConvexBracket(const TriMesh& mesh);

/// Bounds on the distance from point `c` to the body bracketed by the capsules of segment
/// (a, b) with radii `outer_radius_m` >= `inner_radius_m` > 0 (a ConvexBracket moved to c's
/// frame): lower = max(0, D - outer), upper = max(0, D - inner) with D the distance from c to
/// the segment; the axis is the unit direction from the segment's closest point to c (zero when
/// lower is 0). Proof of the axis: every body point x lies within outer of a segment point s,
/// and s . axis <= s* . axis for the segment's closest point s* (projection onto a convex set),
/// so axis . (c - x) >= D - outer. iterations is 0.
/// @rt
[[nodiscard]] DistanceBounds pointConvexBracketBounds(const Eigen::Vector3d& c, const Eigen::Vector3d& a,
                                                      const Eigen::Vector3d& b, double outer_radius_m,
                                                      double inner_radius_m) noexcept;

/// Start vertices for the support climbs (convexSupportVertex) by direction: the unit sphere
/// is split into the cells of a cube map (cells_per_edge x cells_per_edge on each of the six
/// faces) and each cell keeps the vertex farthest along its centre direction (brute force over
/// the vertices that some triangle uses, so a start is never an isolated vertex). A climb from
/// there is exact like any climb and usually ends after its first neighbour scan.
struct SupportTable {
  int cells_per_edge = 0;
  std::vector<int> start_vertex;  ///< 6 x cells_per_edge^2, face-major; empty when not built
};

/// The table of `mesh` (mesh frame). @throws std::invalid_argument when cells_per_edge < 1.
[[nodiscard]] SupportTable buildSupportTable(const TriMesh& mesh, int cells_per_edge);

/// The table's start vertex for `direction` (mesh frame, any nonzero length; a zero or
/// non-finite direction gives the first cell's vertex). @rt
[[nodiscard]] int supportTableStart(const SupportTable& table, const Eigen::Vector3d& direction) noexcept;

/// Bounds on the distance from triangle (t0, t1, t2) to the body bracketed by the capsules of
/// segment (a, b) with radii `outer_radius_m` >= `inner_radius_m` > 0 (a ConvexBracket in the
/// triangle's frame): with q, s the closest points of the triangle and the segment and D = |q -
/// s|, lower = max(0, D - outer) along the axis (q - s)/D, upper = max(0, D - inner). The axis
/// separates: q minimises (q - s) . x over the triangle and s maximises it over the segment
/// (first-order conditions of the closest pair of two convex sets), and every body point lies
/// within outer of the segment. The closest pair is exact (Ericson, Real-Time Collision
/// Detection 5.1.10: the segment crossing the triangle, else the best of the two end points
/// against the triangle and the segment against the three edges). iterations is 0.
/// @rt
[[nodiscard]] DistanceBounds triangleConvexBracketBounds(const Eigen::Vector3d& t0, const Eigen::Vector3d& t1,
                                                         const Eigen::Vector3d& t2, const Eigen::Vector3d& a,
                                                         const Eigen::Vector3d& b, double outer_radius_m,
                                                         double inner_radius_m) noexcept;

/// The vertex graph of `mesh` (vertices joined by an edge of a triangle).
[[nodiscard]] VertexGraph buildVertexGraph(const TriMesh& mesh);

/// The vertex of a closed convex mesh farthest along `direction` (largest vertex . direction),
/// found by climbing the vertex graph from `start`: on a convex body a vertex with no neighbour
/// farther along a direction is farthest overall. `vertices[v]` is mesh vertex v in any frame
/// (`graph` = buildVertexGraph(mesh) gives the adjacency). Precondition: the mesh is closed and
/// convex (SnchTree::convex); on a non-convex mesh the result is a local maximum only.
/// @rt
[[nodiscard]] int convexSupportVertex(const VertexGraph& graph, std::span<const Eigen::Vector3d> vertices,
                                      const Eigen::Vector3d& direction, int start) noexcept;

/// Bounds on the distance between triangle (t0, t1, t2) and the convex body of a closed convex
/// mesh (vertex positions `vertices`, same frame as the triangle): GJK iterates until the
/// bounds are within `tolerance_m` of each other, the lower bound exceeds `stop_above_m`, or no
/// progress is possible (at most 64 support evaluations). The upper bound is the length of a
/// point of the Minkowski difference (a pair of points, one on each body); the lower bound is
/// the largest separation along a GJK direction (a separating plane). Both are rigorous up to
/// rounding. Touching or intersecting bodies give lower_m = 0. `warm_vertex` (in/out) is the
/// mesh vertex the support search starts from; pass any valid vertex id, it is updated to the
/// last support vertex so that nearby queries start close.
/// @rt
[[nodiscard]] DistanceBounds triangleConvexMeshDistanceBounds(const Eigen::Vector3d& t0, const Eigen::Vector3d& t1,
                                                              const Eigen::Vector3d& t2, const VertexGraph& graph,
                                                              std::span<const Eigen::Vector3d> vertices,
                                                              double stop_above_m, double tolerance_m,
                                                              int& warm_vertex) noexcept;

}  // namespace fullarm::haptics
