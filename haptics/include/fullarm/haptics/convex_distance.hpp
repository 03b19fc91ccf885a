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
