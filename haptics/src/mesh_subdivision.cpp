#include "fullarm/haptics/mesh_subdivision.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <utility>
#include <vector>

namespace fullarm::haptics {
namespace {

std::vector<Eigen::Vector3d> meshVertices(const TriMesh& mesh) {
  std::vector<Eigen::Vector3d> v;
  v.reserve(static_cast<std::size_t>(mesh.numVertices()));
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(mesh.vertex(i));
  return v;
}

double edgeLength(const TriMesh& mesh, int e) {
  const auto [a, b] = mesh.edgeVertices(e);
  return (mesh.vertex(a) - mesh.vertex(b)).norm();
}

// Appends the midpoint of every edge with split[e] (or every edge when split is empty) to
// `vertices`; returns the new vertex id per edge (-1 for unsplit edges).
std::vector<int> addMidpoints(const TriMesh& mesh, const std::vector<char>& split,
                              std::vector<Eigen::Vector3d>& vertices) {
  std::vector<int> midpoint(static_cast<std::size_t>(mesh.numEdges()), -1);
  for (int e = 0; e < mesh.numEdges(); ++e) {
    if (!split.empty() && split[static_cast<std::size_t>(e)] == 0) continue;
    const auto [a, b] = mesh.edgeVertices(e);
    midpoint[static_cast<std::size_t>(e)] = static_cast<int>(vertices.size());
    vertices.push_back(0.5 * (mesh.vertex(a) + mesh.vertex(b)));
  }
  return midpoint;
}

}  // namespace

double maxEdgeLength(const TriMesh& mesh) noexcept {
  double longest = 0.0;
  for (int e = 0; e < mesh.numEdges(); ++e) longest = std::max(longest, edgeLength(mesh, e));
  return longest;
}

TriMesh subdivideMidpoint(const TriMesh& mesh, int levels) {
  if (levels < 0) throw MeshError(mesh.source(), "subdivision levels must be >= 0, got " + std::to_string(levels));
  if (static_cast<double>(mesh.numTriangles()) * std::pow(4.0, levels) >
      static_cast<double>(std::numeric_limits<int>::max())) {
    throw MeshError(mesh.source(), std::to_string(levels) + " subdivision levels exceed 2^31 triangles");
  }
  TriMesh current = mesh;
  for (int level = 0; level < levels; ++level) {
    std::vector<Eigen::Vector3d> vertices = meshVertices(current);
    const std::vector<int> mid = addMidpoints(current, {}, vertices);
    std::vector<Eigen::Vector3i> triangles;
    triangles.reserve(4 * static_cast<std::size_t>(current.numTriangles()));
    for (int t = 0; t < current.numTriangles(); ++t) {
      const Eigen::Vector3i& v = current.triangle(t);
      // m[k] is the midpoint of edge k = (v_k, v_{k+1}); the four children keep the winding.
      const int m0 = mid[static_cast<std::size_t>(current.triangleEdge(t, 0))];
      const int m1 = mid[static_cast<std::size_t>(current.triangleEdge(t, 1))];
      const int m2 = mid[static_cast<std::size_t>(current.triangleEdge(t, 2))];
      triangles.emplace_back(v[0], m0, m2);
      triangles.emplace_back(m0, v[1], m1);
      triangles.emplace_back(m2, m1, v[2]);
      triangles.emplace_back(m0, m1, m2);
    }
    current = TriMesh::build(mesh.source(), std::move(vertices), std::move(triangles));
  }
  return current;
}

TriMesh refineLongEdges(const TriMesh& mesh, double max_edge_m) {
  if (!std::isfinite(max_edge_m) || max_edge_m <= 0.0) {
    std::ostringstream msg;
    msg << "refinement edge length must be a finite number > 0 m, got " << max_edge_m;
    throw MeshError(mesh.source(), msg.str());
  }
  TriMesh current = mesh;
  // Every pass at least halves each edge longer than the limit, and new edges are no longer
  // than the longest edge of their triangle: log2(longest / limit) + a few passes suffice.
  constexpr int kMaxPasses = 200;
  for (int pass = 0; pass < kMaxPasses; ++pass) {
    std::vector<char> split(static_cast<std::size_t>(current.numEdges()), 0);
    bool any = false;
    for (int e = 0; e < current.numEdges(); ++e) {
      if (edgeLength(current, e) > max_edge_m) {
        split[static_cast<std::size_t>(e)] = 1;
        any = true;
      }
    }
    if (!any) return current;
    std::vector<Eigen::Vector3d> vertices = meshVertices(current);
    const std::vector<int> mid = addMidpoints(current, split, vertices);
    std::vector<Eigen::Vector3i> triangles;
    triangles.reserve(2 * static_cast<std::size_t>(current.numTriangles()));
    for (int t = 0; t < current.numTriangles(); ++t) {
      const Eigen::Vector3i& v = current.triangle(t);
      int m[3];
      int count = 0;
      for (int k = 0; k < 3; ++k) {
        m[k] = mid[static_cast<std::size_t>(current.triangleEdge(t, k))];
        count += m[k] >= 0 ? 1 : 0;
      }
      if (count == 0) {
        triangles.push_back(v);
      } else if (count == 3) {
        triangles.emplace_back(v[0], m[0], m[2]);
        triangles.emplace_back(m[0], v[1], m[1]);
        triangles.emplace_back(m[2], m[1], v[2]);
        triangles.emplace_back(m[0], m[1], m[2]);
      } else if (count == 1) {
        // Edge k = (v_k, v_k1) split at mk: (v_k, mk, v_k2) and (mk, v_k1, v_k2).
        const int k = m[0] >= 0 ? 0 : (m[1] >= 0 ? 1 : 2);
        const int a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
        triangles.emplace_back(a, m[k], c);
        triangles.emplace_back(m[k], b, c);
      } else {
        // Edges k and k+1 split (the unsplit one is k+2): corner triangle at v_{k+1}, and the
        // quad (v_k, m_k, m_{k+1}, v_{k+2}) cut along its shorter diagonal.
        const int k = m[0] < 0 ? 1 : (m[1] < 0 ? 2 : 0);
        const int a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
        const int mab = m[k], mbc = m[(k + 1) % 3];
        triangles.emplace_back(mab, b, mbc);
        const auto at = [&](int i) -> const Eigen::Vector3d& { return vertices[static_cast<std::size_t>(i)]; };
        if ((at(a) - at(mbc)).squaredNorm() <= (at(mab) - at(c)).squaredNorm()) {
          triangles.emplace_back(a, mab, mbc);
          triangles.emplace_back(a, mbc, c);
        } else {
          triangles.emplace_back(a, mab, c);
          triangles.emplace_back(mab, mbc, c);
        }
      }
    }
    current = TriMesh::build(mesh.source(), std::move(vertices), std::move(triangles));
  }
  throw MeshError(mesh.source(), "edge refinement did not converge");
}

}  // namespace fullarm::haptics
