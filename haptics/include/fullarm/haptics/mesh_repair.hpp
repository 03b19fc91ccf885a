#pragma once
/// @file
/// Repair of double-sided solids: CAD exporters often write a closed solid twice, once per
/// winding, so that renderers without back faces show it from both sides (the DRC valve wall and
/// wheel valve are such files). Every edge of such a mesh has four triangles and every vertex's
/// one-ring holds opposite normals, so no normal-cone bound can prune anything near it
/// (docs/haptics.md, "Double-sided solids"). The repair keeps, for each such solid, the copy whose
/// winding faces outward. The surface (the point set) is unchanged; only the duplicated
/// inward-facing triangles go.

#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// What collapseDoubleSidedSolids found and did.
struct DoubleSidedRepair {
  /// Connected double-sided parts that formed a closed, orientable surface with a positive
  /// enclosed volume after pairing their twins: their inward copies were removed.
  int solids_collapsed = 0;
  /// Triangles removed (one per twin pair of a collapsed solid).
  int triangles_removed = 0;
  /// Of the collapsed solids, those with holes (cracks left by the exporter), and the number of
  /// rim edges of those holes: the kept copy has boundary edges there.
  int solids_with_holes = 0;
  int hole_rim_edges = 0;
  /// Double-sided parts left as they are: open (a sheet, or a solid with a hole), non-manifold,
  /// non-orientable, or enclosing no volume. Their both-side copies are kept, so a minimum may
  /// still be found from either side of them.
  int parts_kept_double_sided = 0;
};

/// Removes the inward-facing copy of every double-sided closed solid in `mesh`.
///
/// Twins are two triangles on the same three vertices with opposite windings. A connected
/// part (connected through edges) is collapsed when every triangle of it has a twin, every edge
/// of it carries two twin pairs or one (a 2-manifold once the pairs are merged, possibly with
/// holes: exporters leave cracks), the merged surface can be oriented consistently (each interior
/// edge traversed once in each direction), and the orientation is unambiguous: the enclosed
/// volume (divergence theorem about the centre of the part's box) exceeds 1e-9 times the cube of
/// the box diagonal and ten times the most that the holes can change it (|S| diag / 3, S the
/// holes' vector area). The orientation with positive volume is kept (outward normals, as for
/// any closed mesh here). Every other part (an open double-sided sheet, a non-manifold or
/// non-orientable part), and every triangle without a twin, is kept unchanged. A cavity
/// modelled as a separate closed part inside a solid would be turned outward as well; such
/// files are not handled (none of the shipped scenes has one). With the inward copy gone, a
/// link entirely inside a collapsed solid, touching nothing, gets no minimum from it (as for any
/// one-sided closed mesh); penetration is reported as a touching minimum as before.
///
/// Vertex ids are unchanged (vertices used only by removed triangles stay, unused); the kept
/// triangles keep their relative order. The result is built with TriMesh::build (no welding:
/// twins are found by vertex id, so weld first).
/// @param report optional: counts of what was done
[[nodiscard]] TriMesh collapseDoubleSidedSolids(const TriMesh& mesh, DoubleSidedRepair* report = nullptr);

}  // namespace fullarm::haptics
