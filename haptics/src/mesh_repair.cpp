#include "fullarm/haptics/mesh_repair.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <limits>
#include <numeric>
#include <vector>

namespace fullarm::haptics {

namespace {

std::array<int, 3> sortedKey(const Eigen::Vector3i& tri) noexcept {
  std::array<int, 3> k{tri[0], tri[1], tri[2]};
  std::sort(k.begin(), k.end());
  return k;
}

// True when triangle `tri` traverses the directed edge u -> w.
bool hasDirectedEdge(const Eigen::Vector3i& tri, int u, int w) noexcept {
  for (int k = 0; k < 3; ++k) {
    if (tri[k] == u && tri[(k + 1) % 3] == w) return true;
  }
  return false;
}

}  // namespace

TriMesh collapseDoubleSidedSolids(const TriMesh& mesh, DoubleSidedRepair* report) {
  DoubleSidedRepair local;
  DoubleSidedRepair& rep = report != nullptr ? *report : local;
  rep = {};
  const int nt = mesh.numTriangles();

  // Twins: exactly two triangles on one vertex set, with opposite windings.
  std::vector<int> order(static_cast<std::size_t>(nt));
  std::iota(order.begin(), order.end(), 0);
  std::vector<std::array<int, 3>> key(static_cast<std::size_t>(nt));
  for (int t = 0; t < nt; ++t) key[static_cast<std::size_t>(t)] = sortedKey(mesh.triangle(t));
  std::stable_sort(order.begin(), order.end(), [&key](int a, int b) {
    return key[static_cast<std::size_t>(a)] < key[static_cast<std::size_t>(b)];
  });
  std::vector<int> twin(static_cast<std::size_t>(nt), -1);
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i + 1;
    while (j < order.size() && key[static_cast<std::size_t>(order[j])] == key[static_cast<std::size_t>(order[i])]) ++j;
    if (j - i == 2) {
      const int a = order[i];
      const int b = order[i + 1];
      const auto& ta = mesh.triangle(a);
      if (!hasDirectedEdge(mesh.triangle(b), ta[0], ta[1])) {  // opposite winding
        twin[static_cast<std::size_t>(a)] = b;
        twin[static_cast<std::size_t>(b)] = a;
      }
    }
    i = j;
  }

  // Parts: triangles connected through shared edges (flood fill over the edge adjacency).
  std::vector<int> part(static_cast<std::size_t>(nt), -1);
  std::vector<int> stack;
  std::vector<std::vector<int>> parts;
  for (int seed = 0; seed < nt; ++seed) {
    if (part[static_cast<std::size_t>(seed)] >= 0) continue;
    const int id = static_cast<int>(parts.size());
    parts.emplace_back();
    part[static_cast<std::size_t>(seed)] = id;
    stack.assign(1, seed);
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      parts.back().push_back(t);
      for (int k = 0; k < 3; ++k) {
        for (int s : mesh.edgeTriangles(mesh.triangleEdge(t, k))) {
          if (part[static_cast<std::size_t>(s)] < 0) {
            part[static_cast<std::size_t>(s)] = id;
            stack.push_back(s);
          }
        }
      }
    }
  }

  // chosen[t]: 1 keep, 0 drop, -1 undecided (within the part being oriented).
  std::vector<signed char> keep(static_cast<std::size_t>(nt), 1);
  std::vector<signed char> chosen(static_cast<std::size_t>(nt), -1);
  for (std::vector<int>& tris : parts) {
    const bool all_twinned =
        std::all_of(tris.begin(), tris.end(), [&twin](int t) { return twin[static_cast<std::size_t>(t)] >= 0; });
    if (!all_twinned) {
      if (std::any_of(tris.begin(), tris.end(), [&twin](int t) { return twin[static_cast<std::size_t>(t)] >= 0; })) {
        ++rep.parts_kept_double_sided;
      }
      continue;
    }
    // A 2-manifold once the pairs are merged: every edge carries two twin pairs (inside the
    // surface) or one (on a hole's rim).
    bool solid = std::all_of(tris.begin(), tris.end(), [&mesh](int t) {
      for (int k = 0; k < 3; ++k) {
        const std::size_t n = mesh.edgeTriangles(mesh.triangleEdge(t, k)).size();
        if (n != 4 && n != 2) return false;
      }
      return true;
    });
    // Orient: propagate a winding from the part's first pair; a neighbour across edge u -> w
    // must traverse w -> u.
    if (solid) {
      const int first = tris.front();
      chosen[static_cast<std::size_t>(first)] = 1;
      chosen[static_cast<std::size_t>(twin[static_cast<std::size_t>(first)])] = 0;
      stack.assign(1, first);
      while (solid && !stack.empty()) {
        const int t = stack.back();
        stack.pop_back();
        const Eigen::Vector3i& tri = mesh.triangle(t);
        for (int k = 0; k < 3 && solid; ++k) {
          const int u = tri[k];
          const int w = tri[(k + 1) % 3];
          for (int s : mesh.edgeTriangles(mesh.triangleEdge(t, k))) {
            if (s == t || s == twin[static_cast<std::size_t>(t)]) continue;
            const bool wanted = hasDirectedEdge(mesh.triangle(s), w, u);
            const signed char c = chosen[static_cast<std::size_t>(s)];
            if (c < 0) {
              chosen[static_cast<std::size_t>(s)] = wanted ? 1 : 0;
              chosen[static_cast<std::size_t>(twin[static_cast<std::size_t>(s)])] = wanted ? 0 : 1;
              stack.push_back(wanted ? s : twin[static_cast<std::size_t>(s)]);
            } else if ((c == 1) != wanted) {
              solid = false;  // non-orientable once merged
              break;
            }
          }
        }
      }
    }
    // Enclosed volume of the kept winding (divergence theorem, origin o at the centre of the
    // part's box). With holes the surface is open and the sum depends on o: moving o by d
    // changes it by -d . S / 3, S the vector area of the holes (half the sum of u x w over their
    // rim edges). The sign is trusted only when the volume exceeds ten times the largest such
    // change for an o anywhere within the part's box diagonal, and 1e-9 diag^3 (not flat).
    double volume = 0.0;
    int rim_edges = 0;
    if (solid) {
      Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
      Eigen::Vector3d hi = -lo;
      for (int t : tris) {
        for (int k = 0; k < 3; ++k) {
          lo = lo.cwiseMin(mesh.vertex(mesh.triangle(t)[k]));
          hi = hi.cwiseMax(mesh.vertex(mesh.triangle(t)[k]));
        }
      }
      const Eigen::Vector3d origin = 0.5 * (lo + hi);
      Eigen::Vector3d hole_area = Eigen::Vector3d::Zero();
      for (int t : tris) {
        if (chosen[static_cast<std::size_t>(t)] != 1) continue;
        const Eigen::Vector3i& tri = mesh.triangle(t);
        const Eigen::Vector3d a = mesh.vertex(tri[0]) - origin;
        const Eigen::Vector3d b = mesh.vertex(tri[1]) - origin;
        const Eigen::Vector3d c = mesh.vertex(tri[2]) - origin;
        volume += a.dot(b.cross(c)) / 6.0;
        for (int k = 0; k < 3; ++k) {
          if (mesh.edgeTriangles(mesh.triangleEdge(t, k)).size() != 2) continue;
          ++rim_edges;
          hole_area += 0.5 * (mesh.vertex(tri[k]) - origin).cross(mesh.vertex(tri[(k + 1) % 3]) - origin);
        }
      }
      const double diag = (hi - lo).norm();
      solid = std::abs(volume) > 1e-9 * diag * diag * diag && std::abs(volume) > 10.0 * hole_area.norm() * diag / 3.0;
    }
    if (!solid) {
      ++rep.parts_kept_double_sided;
      continue;
    }
    if (rim_edges > 0) {
      ++rep.solids_with_holes;
      rep.hole_rim_edges += rim_edges;
    }
    const signed char outward = volume > 0.0 ? 1 : 0;
    for (int t : tris) keep[static_cast<std::size_t>(t)] = chosen[static_cast<std::size_t>(t)] == outward ? 1 : 0;
    ++rep.solids_collapsed;
    rep.triangles_removed += static_cast<int>(tris.size() / 2);
  }
  if (rep.solids_collapsed == 0) return mesh;

  std::vector<Eigen::Vector3d> vertices(static_cast<std::size_t>(mesh.numVertices()));
  for (int v = 0; v < mesh.numVertices(); ++v) vertices[static_cast<std::size_t>(v)] = mesh.vertex(v);
  std::vector<Eigen::Vector3i> triangles;
  triangles.reserve(static_cast<std::size_t>(nt - rep.triangles_removed));
  for (int t = 0; t < nt; ++t) {
    if (keep[static_cast<std::size_t>(t)] != 0) triangles.push_back(mesh.triangle(t));
  }
  return TriMesh::build(mesh.source(), std::move(vertices), std::move(triangles), 0.0);
}

}  // namespace fullarm::haptics
