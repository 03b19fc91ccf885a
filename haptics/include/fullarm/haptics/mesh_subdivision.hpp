#pragma once
/// @file
/// Midpoint subdivision of triangle meshes: uniform 1-to-4 refinement (to scale a scene's
/// triangle count for benchmarks) and conforming refinement of long edges (so bounding-volume
/// hierarchies get tight nodes on CAD meshes made of long sliver triangles). Both keep the
/// surface exactly: new vertices are edge midpoints of flat triangles.

#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// Splits every triangle into four at its edge midpoints, `levels` times (x 4^levels
/// triangles). Shared edges get one midpoint, so the result has no T-junctions.
/// @param levels >= 0
/// @throws MeshError if levels < 0 or the result would exceed 2^31 - 1 triangles
[[nodiscard]] TriMesh subdivideMidpoint(const TriMesh& mesh, int levels);

/// Splits every edge longer than `max_edge_m` at its midpoint, repeatedly, until no edge is
/// longer; each triangle is re-triangulated by the pattern of its split edges (one split: two
/// triangles; two: three, cutting the quad along its shorter diagonal; three: four), so the
/// refinement conforms (no T-junctions) and only long edges are refined.
/// @param max_edge_m > 0 [m]
/// @throws MeshError if max_edge_m is not a finite number > 0
[[nodiscard]] TriMesh refineLongEdges(const TriMesh& mesh, double max_edge_m);

/// Largest edge length of a mesh [m].
[[nodiscard]] double maxEdgeLength(const TriMesh& mesh) noexcept;

}  // namespace fullarm::haptics
