#pragma once
/// @file
/// Triangle-mesh import from files (COLLADA .dae, Wavefront .obj, STL, PLY) through assimp 5.2,
/// with unit scale, a pose, and vertex welding, into a validated TriMesh.

#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <string_view>

#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// Default weld tolerance of importMesh [m]: merges the copies of a vertex that exporters write
/// once per face (for per-face normals or texture seams) and the float round-off between
/// sub-meshes of one file, while staying far below any feature of a CAD model.
inline constexpr double kDefaultImportWeldToleranceM = 1e-6;

/// How a file's coordinates become metres in the mesh (object) frame O.
///
/// Vertex p_F read from the file (after the file's node hierarchy, and for COLLADA after its
/// own `<unit meter=...>` and `<up_axis>`) becomes p_O = X_OF * (scale * p_F).
struct MeshImportOptions {
  /// Metres per file unit, applied on top of the file's own unit. COLLADA files declare their
  /// unit, so 1 is right for them; STL, OBJ and PLY have none: e.g. 0.001 for millimetres.
  double scale = 1.0;
  /// Pose of the file's frame F in the mesh frame O (applied after scaling).
  Eigen::Isometry3d X_OF = Eigen::Isometry3d::Identity();
  /// Vertices closer than this are merged (TriMesh::build); 0 disables welding [m].
  double weld_tolerance_m = kDefaultImportWeldToleranceM;
  /// Keep only the outward copy of every double-sided closed solid (collapseDoubleSidedSolids,
  /// after welding, before refinement): the surface is unchanged, and normal cones can prune
  /// near it again. False keeps the file's triangles as they are.
  bool collapse_double_sided_solids = true;
  /// When > 0, edges longer than this are split at their midpoints after welding
  /// (refineLongEdges): CAD exports often span flat faces with long sliver triangles, whose
  /// bounding spheres are as large as the face and defeat hierarchy culling [m].
  double max_edge_m = 0.0;
  /// Longest time the file reader may take before the file is declared malformed [s].
  double time_limit_s = 60.0;
};

/// True for the extensions importMesh accepts: .dae, .obj, .stl, .ply (any letter case).
[[nodiscard]] bool isSupportedMeshFile(const std::filesystem::path& file);

/// Reads a triangle mesh from a file.
///
/// Conventions: fullarm frames are z up. A COLLADA file is rotated from its `<up_axis>`
/// (Y_UP, Z_UP or X_UP) to z up and scaled by its `<unit meter=...>`, so a Z_UP file in inches
/// comes out in metres with its axes unchanged (as Gazebo shows it). OBJ, STL and PLY files
/// are taken as they are (no unit, no up axis). Every node of the file's scene graph is
/// flattened with its transform (instanced meshes appear once per instance); polygons are
/// triangulated; point and line primitives are ignored. Vertex welding, degenerate-triangle
/// repair and validation are those of TriMesh::build (source = the file path); then, unless
/// disabled, double-sided closed solids keep only their outward copy (mesh_repair.hpp).
///
/// Isolation: assimp 5.2 hangs or crashes on some truncated or mutated files (found by
/// tests/haptics/mesh_import_test.cpp: PLY headers, COLLADA arrays without a count). The file
/// is therefore read in a forked child process that sends the triangles back through a pipe;
/// a crash or a reader running past `time_limit_s` becomes a MeshError, and the calling process
/// is never affected. PLY headers are also checked before assimp sees them.
///
/// @param file a .dae, .obj, .stl or .ply file
/// @throws MeshError (naming the file) if the file does not exist or cannot be read, has an
///   unsupported extension, is malformed or truncated (assimp's message is included), holds no
///   triangle, holds a non-finite coordinate or transform, makes the reader crash or run past
///   the time limit, or if the options are invalid (scale not finite and > 0, X_OF not a
///   finite rigid transform, negative weld tolerance or max_edge_m, time limit not > 0).
[[nodiscard]] TriMesh importMesh(const std::filesystem::path& file, const MeshImportOptions& options = {});

}  // namespace fullarm::haptics
