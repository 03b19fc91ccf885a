#include "fullarm/haptics/tri_mesh.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <tuple>
#include <unordered_map>

namespace fullarm::haptics {

MeshError::MeshError(const std::string& source, const std::string& defect)
    : std::runtime_error(source + ": " + defect), source_(source) {}

namespace {

std::string vecString(const Eigen::Vector3d& v) {
  std::ostringstream s;
  s << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return s.str();
}

// Merges vertices closer than `tol` (union into the lowest index of a spatial-hash cell
// neighbourhood); returns the map old index -> new index and compacts `vertices`.
std::vector<int> weldVertices(std::vector<Eigen::Vector3d>& vertices, double tol, int& welded) {
  const std::size_t n = vertices.size();
  std::vector<int> remap(n, -1);
  struct KeyHash {
    std::size_t operator()(const std::tuple<long long, long long, long long>& k) const noexcept {
      const auto [x, y, z] = k;
      // Unsigned arithmetic: the products wrap instead of overflowing.
      return static_cast<std::size_t>(static_cast<unsigned long long>(x) * 73856093ULL ^
                                      static_cast<unsigned long long>(y) * 19349663ULL ^
                                      static_cast<unsigned long long>(z) * 83492791ULL);
    }
  };
  std::unordered_map<std::tuple<long long, long long, long long>, std::vector<int>, KeyHash> cells;
  std::vector<Eigen::Vector3d> kept;
  auto cellOf = [tol](const Eigen::Vector3d& p) {
    return std::make_tuple(static_cast<long long>(std::floor(p.x() / tol)),
                           static_cast<long long>(std::floor(p.y() / tol)),
                           static_cast<long long>(std::floor(p.z() / tol)));
  };
  for (std::size_t i = 0; i < n; ++i) {
    const auto [cx, cy, cz] = cellOf(vertices[i]);
    int found = -1;
    for (long long dx = -1; dx <= 1 && found < 0; ++dx) {
      for (long long dy = -1; dy <= 1 && found < 0; ++dy) {
        for (long long dz = -1; dz <= 1 && found < 0; ++dz) {
          const auto it = cells.find({cx + dx, cy + dy, cz + dz});
          if (it == cells.end()) continue;
          for (int k : it->second) {
            if ((kept[static_cast<std::size_t>(k)] - vertices[i]).norm() <= tol) {
              found = k;
              break;
            }
          }
        }
      }
    }
    if (found < 0) {
      found = static_cast<int>(kept.size());
      kept.push_back(vertices[i]);
      cells[{cx, cy, cz}].push_back(found);
    } else {
      ++welded;
    }
    remap[i] = found;
  }
  vertices = std::move(kept);
  return remap;
}

}  // namespace

TriMesh TriMesh::build(std::string source, std::vector<Eigen::Vector3d> vertices_m,
                       std::vector<Eigen::Vector3i> triangles, double weld_tolerance_m) {
  TriMesh mesh;
  mesh.source_ = std::move(source);
  if (!std::isfinite(weld_tolerance_m) || weld_tolerance_m < 0.0) {
    throw MeshError(mesh.source_,
                    "weld tolerance must be a finite value >= 0 m, got " + std::to_string(weld_tolerance_m));
  }
  const int nv = static_cast<int>(vertices_m.size());
  for (int v = 0; v < nv; ++v) {
    if (!vertices_m[static_cast<std::size_t>(v)].allFinite()) {
      throw MeshError(mesh.source_, "vertex " + std::to_string(v) + " has a non-finite coordinate " +
                                        vecString(vertices_m[static_cast<std::size_t>(v)]));
    }
  }
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int v = triangles[t][k];
      if (v < 0 || v >= nv) {
        throw MeshError(mesh.source_, "triangle " + std::to_string(t) + " references vertex " + std::to_string(v) +
                                          ", expected an index in [0, " + std::to_string(nv) + ")");
      }
    }
  }
  if (weld_tolerance_m > 0.0) {
    // Welding bins vertices into integer cells of the tolerance's size: a coordinate more than
    // 2^50 cells from the origin has no exact cell index (and would overflow it), so it is an error.
    const double max_cells = std::ldexp(1.0, 50);
    for (int v = 0; v < nv; ++v) {
      if (vertices_m[static_cast<std::size_t>(v)].cwiseAbs().maxCoeff() / weld_tolerance_m >= max_cells) {
        throw MeshError(mesh.source_,
                        "vertex " + std::to_string(v) + " " + vecString(vertices_m[static_cast<std::size_t>(v)]) +
                            " is too far from the origin to weld at a tolerance of " +
                            std::to_string(weld_tolerance_m) + " m: expected |coordinate| / tolerance < 2^50");
      }
    }
    const std::vector<int> remap = weldVertices(vertices_m, weld_tolerance_m, mesh.welded_vertices_);
    for (auto& tri : triangles) {
      for (int k = 0; k < 3; ++k) tri[k] = remap[static_cast<std::size_t>(tri[k])];
    }
  }
  mesh.vertices_ = std::move(vertices_m);

  // Degenerate triangles: repeated index or (near-)zero area relative to the mesh size.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (const auto& v : mesh.vertices_) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const double diag2 = mesh.vertices_.empty() ? 0.0 : (hi - lo).squaredNorm();
  mesh.triangles_.reserve(triangles.size());
  for (const auto& tri : triangles) {
    const Eigen::Vector3d& a = mesh.vertices_[static_cast<std::size_t>(tri[0])];
    const Eigen::Vector3d& b = mesh.vertices_[static_cast<std::size_t>(tri[1])];
    const Eigen::Vector3d& c = mesh.vertices_[static_cast<std::size_t>(tri[2])];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const bool repeated = tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2];
    if (repeated || 0.5 * n.norm() <= kDegenerateAreaRel * diag2) {
      ++mesh.repaired_degenerate_;
      continue;
    }
    mesh.triangles_.push_back(tri);
    mesh.normals_.push_back(n.normalized());
  }
  if (mesh.triangles_.empty()) {
    throw MeshError(mesh.source_, "no valid triangle (" + std::to_string(triangles.size()) + " given, " +
                                      std::to_string(mesh.repaired_degenerate_) + " degenerate)");
  }
  const int nt = mesh.numTriangles();

  // Edges: sort the 3 nt half-edges by their undirected vertex pair.
  struct HalfEdge {
    int a, b, tri, k;
  };
  std::vector<HalfEdge> half;
  half.reserve(static_cast<std::size_t>(3 * nt));
  for (int t = 0; t < nt; ++t) {
    const auto& tri = mesh.triangles_[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      const int u = tri[k];
      const int w = tri[(k + 1) % 3];
      half.push_back({std::min(u, w), std::max(u, w), t, k});
    }
  }
  std::vector<int> order(half.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&half](int i, int j) {
    const auto& x = half[static_cast<std::size_t>(i)];
    const auto& y = half[static_cast<std::size_t>(j)];
    return std::tie(x.a, x.b, x.tri) < std::tie(y.a, y.b, y.tri);
  });
  // Group runs; edge ids in order of first appearance (by triangle, then k).
  std::vector<int> group_of(half.size(), -1);
  std::vector<std::pair<int, int>> groups;  // [begin, end) in `order`
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i + 1;
    const auto& h = half[static_cast<std::size_t>(order[i])];
    while (j < order.size() && half[static_cast<std::size_t>(order[j])].a == h.a &&
           half[static_cast<std::size_t>(order[j])].b == h.b) {
      ++j;
    }
    for (std::size_t m = i; m < j; ++m) group_of[static_cast<std::size_t>(order[m])] = static_cast<int>(groups.size());
    groups.emplace_back(static_cast<int>(i), static_cast<int>(j));
    i = j;
  }
  std::vector<int> group_to_edge(groups.size(), -1);
  mesh.triangle_edges_.resize(static_cast<std::size_t>(nt));
  for (std::size_t h = 0; h < half.size(); ++h) {
    const int g = group_of[h];
    int& e = group_to_edge[static_cast<std::size_t>(g)];
    if (e < 0) {
      e = mesh.numEdges();
      mesh.edge_vertices_.push_back({half[h].a, half[h].b});
    }
    mesh.triangle_edges_[static_cast<std::size_t>(half[h].tri)][static_cast<std::size_t>(half[h].k)] = e;
  }
  const int ne = mesh.numEdges();
  std::vector<int> edge_to_group(static_cast<std::size_t>(ne));
  for (std::size_t g = 0; g < groups.size(); ++g)
    edge_to_group[static_cast<std::size_t>(group_to_edge[g])] = static_cast<int>(g);
  mesh.edge_tri_offsets_.assign(1, 0);
  for (int e = 0; e < ne; ++e) {
    const auto [b, en] = groups[static_cast<std::size_t>(edge_to_group[static_cast<std::size_t>(e)])];
    for (int m = b; m < en; ++m)
      mesh.edge_tris_.push_back(half[static_cast<std::size_t>(order[static_cast<std::size_t>(m)])].tri);
    mesh.edge_tri_offsets_.push_back(static_cast<int>(mesh.edge_tris_.size()));
    const int count = en - b;
    if (count == 1) ++mesh.boundary_edges_;
    if (count > 2) ++mesh.non_manifold_edges_;
  }

  // Vertex one-rings (CSR).
  const int nv2 = mesh.numVertices();
  mesh.vertex_tri_offsets_.assign(static_cast<std::size_t>(nv2) + 1, 0);
  for (const auto& tri : mesh.triangles_) {
    for (int k = 0; k < 3; ++k) ++mesh.vertex_tri_offsets_[static_cast<std::size_t>(tri[k]) + 1];
  }
  for (int v = 0; v < nv2; ++v) {
    mesh.vertex_tri_offsets_[static_cast<std::size_t>(v) + 1] += mesh.vertex_tri_offsets_[static_cast<std::size_t>(v)];
  }
  mesh.vertex_tris_.resize(static_cast<std::size_t>(3 * nt));
  std::vector<int> fill(mesh.vertex_tri_offsets_.begin(), mesh.vertex_tri_offsets_.end() - 1);
  for (int t = 0; t < nt; ++t) {
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<std::size_t>(mesh.triangles_[static_cast<std::size_t>(t)][k]);
      mesh.vertex_tris_[static_cast<std::size_t>(fill[v]++)] = t;
    }
  }

  // Feature pseudo-normals: edges sum their face normals, vertices weight by incident angle.
  mesh.edge_normals_.resize(static_cast<std::size_t>(ne));
  for (int e = 0; e < ne; ++e) {
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    for (int t : mesh.edgeTriangles(e)) s += mesh.faceNormal(t);
    mesh.edge_normals_[static_cast<std::size_t>(e)] = s.norm() > 1e-12 ? s.normalized() : Eigen::Vector3d::Zero();
  }
  mesh.vertex_normals_.assign(static_cast<std::size_t>(nv2), Eigen::Vector3d::Zero());
  for (int t = 0; t < nt; ++t) {
    const auto& tri = mesh.triangles_[static_cast<std::size_t>(t)];
    for (int k = 0; k < 3; ++k) {
      const Eigen::Vector3d& p = mesh.vertex(tri[k]);
      const Eigen::Vector3d e1 = (mesh.vertex(tri[(k + 1) % 3]) - p).normalized();
      const Eigen::Vector3d e2 = (mesh.vertex(tri[(k + 2) % 3]) - p).normalized();
      const double angle = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
      mesh.vertex_normals_[static_cast<std::size_t>(tri[k])] += angle * mesh.faceNormal(t);
    }
  }
  for (auto& n : mesh.vertex_normals_) n = n.norm() > 1e-12 ? n.normalized() : Eigen::Vector3d::Zero();
  return mesh;
}

std::span<const int> TriMesh::edgeTriangles(int e) const noexcept {
  const auto b = static_cast<std::size_t>(edge_tri_offsets_[static_cast<std::size_t>(e)]);
  const auto en = static_cast<std::size_t>(edge_tri_offsets_[static_cast<std::size_t>(e) + 1]);
  return {edge_tris_.data() + b, en - b};
}

std::span<const int> TriMesh::vertexTriangles(int v) const noexcept {
  const auto b = static_cast<std::size_t>(vertex_tri_offsets_[static_cast<std::size_t>(v)]);
  const auto en = static_cast<std::size_t>(vertex_tri_offsets_[static_cast<std::size_t>(v) + 1]);
  return {vertex_tris_.data() + b, en - b};
}

std::span<const int> TriMesh::featureTriangles(const Feature& f) const noexcept {
  switch (f.kind) {
    case FeatureKind::kEdge:
      return edgeTriangles(f.index);
    case FeatureKind::kVertex:
      return vertexTriangles(f.index);
    case FeatureKind::kFace:
      break;
  }
  // A triangle appears in the one-ring of its first vertex; point into that storage.
  const auto v = static_cast<std::size_t>(triangles_[static_cast<std::size_t>(f.index)][0]);
  for (auto i = static_cast<std::size_t>(vertex_tri_offsets_[v]);
       i < static_cast<std::size_t>(vertex_tri_offsets_[v + 1]); ++i) {
    if (vertex_tris_[i] == f.index) return {vertex_tris_.data() + i, 1};
  }
  return {};
}

// G5: angle-weighted pseudo-normal (reports/equations.md).
const Eigen::Vector3d& TriMesh::featureNormal(const Feature& f) const noexcept {
  switch (f.kind) {
    case FeatureKind::kEdge:
      return edge_normals_[static_cast<std::size_t>(f.index)];
    case FeatureKind::kVertex:
      return vertex_normals_[static_cast<std::size_t>(f.index)];
    case FeatureKind::kFace:
      break;
  }
  return normals_[static_cast<std::size_t>(f.index)];
}

double TriMesh::area() const noexcept {
  double a = 0.0;
  for (const auto& tri : triangles_) {
    a += 0.5 * (vertex(tri[1]) - vertex(tri[0])).cross(vertex(tri[2]) - vertex(tri[0])).norm();
  }
  return a;
}

}  // namespace fullarm::haptics
