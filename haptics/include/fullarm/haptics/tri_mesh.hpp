#pragma once
/// @file
/// TriMesh: an immutable, validated triangle mesh with edge and vertex adjacency, and the
/// feature vocabulary (face / edge / vertex) that every distance query of the haptics module
/// reports.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace fullarm::haptics {

/// Which kind of mesh feature a closest point lies on.
enum class FeatureKind : std::uint8_t { kFace, kEdge, kVertex };

/// A mesh feature. `index` is a triangle id (kFace), a TriMesh edge id (kEdge) or a vertex id
/// (kVertex).
struct Feature {
  FeatureKind kind = FeatureKind::kFace;
  int index = -1;
  friend bool operator==(const Feature&, const Feature&) = default;
};

/// Thrown when a mesh cannot be built. what() reads `<source>: <defect>`, where the source is
/// the file or builder the mesh came from and the defect names the element (vertex/triangle
/// index) and what was expected.
class MeshError : public std::runtime_error {
 public:
  MeshError(const std::string& source, const std::string& defect);
  [[nodiscard]] const std::string& source() const noexcept { return source_; }

 private:
  std::string source_;
};

/// A triangle mesh in its own frame (metres), immutable after build().
///
/// Validation and repair done by build():
/// - a non-finite vertex coordinate, a triangle index out of range, or a mesh with no
///   triangle left -> MeshError;
/// - degenerate triangles (two equal indices, or area below kDegenerateAreaRel times the
///   squared bounding-box diagonal) are dropped and counted (repairedDegenerateCount());
/// - vertices closer than `weld_tolerance_m` are welded when the tolerance is positive
///   (otherwise duplicates are kept: a seam then looks like a boundary);
/// - non-manifold edges (more than two triangles) are kept: edgeTriangles() lists all of them
///   and every query treats the edge's neighbourhood as the union of those triangles;
/// - vertices that no triangle uses are kept (empty one-ring) so vertex ids stay stable.
///
/// Edge ids are assigned in order of first appearance; edge k of triangle t joins
/// triangle(t)[k] and triangle(t)[(k+1)%3].
class TriMesh {
 public:
  /// Relative area threshold below which a triangle counts as degenerate.
  static constexpr double kDegenerateAreaRel = 1e-14;

  /// Builds and validates a mesh. `source` names the file or builder for error messages.
  /// @param vertices_m vertex positions [m] in the mesh frame
  /// @param triangles  vertex indices, counter-clockwise seen from outside (right-hand normal)
  /// @param weld_tolerance_m vertices closer than this are merged (0: no welding)
  /// @throws MeshError on non-finite coordinates, out-of-range indices, no valid triangle,
  ///         or a negative/non-finite weld tolerance
  static TriMesh build(std::string source, std::vector<Eigen::Vector3d> vertices_m,
                       std::vector<Eigen::Vector3i> triangles, double weld_tolerance_m = 0.0);

  TriMesh() = default;

  [[nodiscard]] int numVertices() const noexcept { return static_cast<int>(vertices_.size()); }
  [[nodiscard]] int numTriangles() const noexcept { return static_cast<int>(triangles_.size()); }
  [[nodiscard]] int numEdges() const noexcept { return static_cast<int>(edge_vertices_.size()); }

  [[nodiscard]] const Eigen::Vector3d& vertex(int v) const noexcept { return vertices_[static_cast<std::size_t>(v)]; }
  [[nodiscard]] const Eigen::Vector3i& triangle(int t) const noexcept {
    return triangles_[static_cast<std::size_t>(t)];
  }
  /// Unit face normal (right-hand rule over the triangle's vertex order).
  [[nodiscard]] const Eigen::Vector3d& faceNormal(int t) const noexcept {
    return normals_[static_cast<std::size_t>(t)];
  }
  /// Edge id of edge k (0..2) of triangle t: the edge (v_k, v_{k+1 mod 3}).
  [[nodiscard]] int triangleEdge(int t, int k) const noexcept {
    return triangle_edges_[static_cast<std::size_t>(t)][static_cast<std::size_t>(k)];
  }
  /// Triangles sharing edge e: one (boundary), two (manifold) or more (non-manifold).
  [[nodiscard]] std::span<const int> edgeTriangles(int e) const noexcept;
  /// The two vertex ids of edge e, smaller first.
  [[nodiscard]] std::array<int, 2> edgeVertices(int e) const noexcept {
    return edge_vertices_[static_cast<std::size_t>(e)];
  }
  /// Triangles that use vertex v (its one-ring).
  [[nodiscard]] std::span<const int> vertexTriangles(int v) const noexcept;
  /// Triangles incident to a feature: the triangle itself, the edge's triangles or the
  /// vertex's one-ring.
  [[nodiscard]] std::span<const int> featureTriangles(const Feature& f) const noexcept;
  /// Unit pseudo-normal of a feature (Baerentzen-Aanaes): the face normal; the normalised sum
  /// of the edge's face normals; the angle-weighted sum of the vertex's face normals. Zero when
  /// the normals cancel. Mesh frame.
  [[nodiscard]] const Eigen::Vector3d& featureNormal(const Feature& f) const noexcept;

  /// File or builder the mesh came from.
  [[nodiscard]] const std::string& source() const noexcept { return source_; }
  [[nodiscard]] int repairedDegenerateCount() const noexcept { return repaired_degenerate_; }
  [[nodiscard]] int weldedVertexCount() const noexcept { return welded_vertices_; }
  [[nodiscard]] int boundaryEdgeCount() const noexcept { return boundary_edges_; }
  [[nodiscard]] int nonManifoldEdgeCount() const noexcept { return non_manifold_edges_; }
  /// Total surface area [m^2].
  [[nodiscard]] double area() const noexcept;

 private:
  std::string source_;
  std::vector<Eigen::Vector3d> vertices_;
  std::vector<Eigen::Vector3i> triangles_;
  std::vector<Eigen::Vector3d> normals_;
  std::vector<std::array<int, 3>> triangle_edges_;
  std::vector<std::array<int, 2>> edge_vertices_;
  std::vector<int> edge_tri_offsets_, edge_tris_;      // CSR: edge -> triangles
  std::vector<int> vertex_tri_offsets_, vertex_tris_;  // CSR: vertex -> triangles
  std::vector<Eigen::Vector3d> edge_normals_, vertex_normals_;
  int repaired_degenerate_ = 0;
  int welded_vertices_ = 0;
  int boundary_edges_ = 0;
  int non_manifold_edges_ = 0;
};

}  // namespace fullarm::haptics
