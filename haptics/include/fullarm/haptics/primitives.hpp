#pragma once
/// @file
/// Closed, outward-wound triangle meshes of simple solids, and the arm's link meshes.
///
/// Flat faces are split into grids of squares no larger than `max_edge_m` (the resolution
/// parameter), so the same solid can be built coarse or densely triangulated. Curved surfaces
/// take a segment count. Every builder validates its arguments and throws MeshError naming
/// the builder and the argument. Frames: each solid is centred at its frame origin unless
/// stated otherwise.

#include <Eigen/Geometry>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// Box with edge lengths `size_m` (x, y, z), centred at the origin.
/// @param max_edge_m longest grid edge on the faces [m], > 0
[[nodiscard]] TriMesh makeBox(const Eigen::Vector3d& size_m, double max_edge_m);

/// Capsule: the points within `radius_m` of segment [from_m, to_m].
/// @param segments around the axis (>= 3); @param rings per hemisphere (>= 1)
[[nodiscard]] TriMesh makeCapsule(const Eigen::Vector3d& from_m, const Eigen::Vector3d& to_m, double radius_m,
                                  int segments, int rings);

/// Closed cylinder along z from z = -length/2 to +length/2.
/// @param segments around the axis (>= 3); @param max_edge_m axial grid edge [m]
[[nodiscard]] TriMesh makeCylinder(double radius_m, double length_m, int segments, double max_edge_m);

/// Rectangular frame (a wall opening's surround): the solid between an outer and an inner
/// rectangle in the x-y plane, extruded over `depth_m` along z (centred). The opening is the
/// inner rectangle.
[[nodiscard]] TriMesh makeRectangularFrame(double outer_width_m, double outer_height_m, double bar_width_m,
                                           double depth_m, double max_edge_m);

/// I-beam along z (centred): flanges of width `flange_width_m` and thickness
/// `flange_thickness_m` at y = +-height/2, web of thickness `web_thickness_m`.
[[nodiscard]] TriMesh makeIBeam(double height_m, double flange_width_m, double flange_thickness_m,
                                double web_thickness_m, double length_m, double max_edge_m);

/// Mesh of one arm link in its link frame: the capsule of its LinkGeometry. Links without
/// capsule geometry have no mesh here (mesh links are imported by mesh_import).
/// @throws MeshError if the link's geometry is not a capsule
[[nodiscard]] TriMesh makeLinkCapsuleMesh(const arm::ArmModel& model, int link, int segments, int rings);

}  // namespace fullarm::haptics
