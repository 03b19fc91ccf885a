#pragma once
/// @file
/// Neighbour-rejection cones: a per-vertex and per-edge precomputation that lets local descent
/// reject every neighbour triangle of a closest feature with one dot product.
///
/// Local descent screens the triangles around a closest vertex or edge x: a neighbour triangle
/// t can lower the distance only if some direction into t from x has a positive component
/// along the direction `dir` towards the other mesh (first-order test, exact because the
/// distance over a flat triangle is convex). For a vertex v the directions into its one-ring
/// are spanned by the one-ring edges w - v; for an edge they are the in-plane directions of its
/// triangles perpendicular to it. The set of `dir` that no such direction points along (the
/// polar cone of the constraint vectors) is fixed by the mesh. This file stores, per feature,
/// a circular cone {dir : dir . axis >= cos alpha} inside that polar cone, shrunk by a margin
/// that covers the rounding of the per-triangle test. When `dir` lies in the cone, every
/// neighbour would be rejected by the per-triangle test, so none needs to be looked at; when
/// it does not, the caller runs the per-triangle test (the cone is a sufficient condition,
/// never a necessary one). A feature whose constraint vectors do not fit in an open half-space
/// (a saddle vertex, a flat vertex, a vertex of a two-sided sheet) gets no cone.

#include <Eigen/Core>
#include <vector>

#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// Rejection cones of one mesh, indexed by vertex id and edge id (mesh frame). Each entry is
/// (axis * s, cos alpha * s) in single precision for some scale s > 0 (the float-rounded axis
/// is not exactly unit; the stored threshold accounts for it and is rounded towards the
/// smaller cone). An entry whose w exceeds every possible dir . axis (w = 2) is "no cone".
struct NeighbourCones {
  std::vector<Eigen::Vector4f> vertex;  ///< one per mesh vertex
  std::vector<Eigen::Vector4f> edge;    ///< one per mesh edge
};

/// Builds the rejection cones of every vertex and edge of `mesh` (O(triangles)). For each
/// feature two axes are tried (the feature pseudo-normal and the negated mean of the unit
/// constraint vectors) and the one with the wider cone is kept. The half-angle alpha is the
/// smallest angle between the cone and the constraint vectors' orthogonal planes, minus a
/// rounding margin of 1e-12 (|w| + |x|) / |g| + 1e-9 rad per constraint vector g (w, x the
/// coordinates entering the per-triangle test); a feature with alpha below 1e-4 rad gets none.
/// Memory: 16 bytes per vertex and per edge.
[[nodiscard]] NeighbourCones computeNeighbourCones(const TriMesh& mesh);

/// True when `dir` (unit, mesh frame) lies inside the rejection cone of feature `f` (a vertex
/// or an edge of the mesh the cones were built for): then no neighbour triangle of f passes
/// the first-order screening test. False for a face, for a feature without a cone, and
/// whenever dir lies outside the cone (the caller must then screen each neighbour).
/// @rt
[[nodiscard]] inline bool conesRejectAllNeighbours(const NeighbourCones& cones, const Feature& f,
                                                   const Eigen::Vector3d& dir) noexcept {
  const Eigen::Vector4f* c = nullptr;
  if (f.kind == FeatureKind::kVertex) {
    c = &cones.vertex[static_cast<std::size_t>(f.index)];
  } else if (f.kind == FeatureKind::kEdge) {
    c = &cones.edge[static_cast<std::size_t>(f.index)];
  } else {
    return false;
  }
  const double along = dir.x() * static_cast<double>((*c)[0]) + dir.y() * static_cast<double>((*c)[1]) +
                       dir.z() * static_cast<double>((*c)[2]);
  return along >= static_cast<double>((*c)[3]);
}

}  // namespace fullarm::haptics
