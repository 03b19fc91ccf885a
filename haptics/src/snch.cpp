#include "fullarm/haptics/snch.hpp"

#include "fullarm/haptics/convex_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <thread>
#include <tuple>

namespace fullarm::haptics {

using Eigen::Isometry3d;
using Eigen::Vector3d;

namespace {

constexpr double kPi = std::numbers::pi;

struct Cone {
  Vector3d axis = Vector3d::UnitZ();
  double half_angle = 0.0;
  bool two_sided = false;  // the double cone +-axis
};

double angleBetween(const Vector3d& a, const Vector3d& b) noexcept {
  // atan2 form: accurate for small and large angles.
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Smallest cone around both cones with the axis in their common plane (the tight merge of
// bounding cones: keep the wider one if it covers the other, else widen towards the other).
Cone mergeOneSided(const Cone& a, const Cone& b) noexcept {
  if (a.half_angle >= kPi || b.half_angle >= kPi) return {a.axis, kPi};
  const double theta = angleBetween(a.axis, b.axis);
  if (theta + b.half_angle <= a.half_angle) return a;
  if (theta + a.half_angle <= b.half_angle) return b;
  const double alpha = 0.5 * (a.half_angle + theta + b.half_angle);
  if (alpha >= kPi) return {a.axis, kPi};
  // Rotate a's axis towards b's by alpha - a.half_angle.
  Vector3d w = b.axis - a.axis.dot(b.axis) * a.axis;
  w = w.norm() > 1e-12 ? Vector3d(w.normalized()) : a.axis.unitOrthogonal();
  const double delta = alpha - a.half_angle;
  return {(std::cos(delta) * a.axis + std::sin(delta) * w).normalized(), alpha};
}

// A double cone holds every direction once its half angle (with the slack) reaches pi/2.
Cone fullIfWide(Cone c) noexcept {
  if (c.two_sided && c.half_angle + kConeSlack_rad >= 0.5 * kPi) return {c.axis, kPi};
  return c;
}

// Merge; with a double cone on either side the result is a double cone around both (b's axis
// turned towards a's first).
Cone mergeCones(const Cone& a, Cone b) noexcept {
  if (!a.two_sided && !b.two_sided) return mergeOneSided(a, b);
  if (a.half_angle >= kPi || b.half_angle >= kPi) return {a.axis, kPi};
  if (a.axis.dot(b.axis) < 0.0) b.axis = -b.axis;
  Cone m = mergeOneSided(a, b);
  m.two_sided = true;
  return fullIfWide(m);
}

// Feasibility slack of the normal-cone constraints u . e <= 0 (unit vectors).
constexpr double kRayTolerance = 1e-9;

// Spanning rays of the normal cone {u : u . e <= 0 for every e in `dirs`} (unit directions from
// a vertex along its edges). Returns false when that cone is neither pointed nor a line (then
// no bounded cone holds it); a line gives its two opposite rays; an empty `rays` is the cone
// {0}.
bool vertexNormalConeRays(const std::vector<Vector3d>& dirs, std::vector<Vector3d>& rays) {
  rays.clear();
  auto feasible = [&](const Vector3d& r) {
    return std::all_of(dirs.begin(), dirs.end(), [&](const Vector3d& e) { return r.dot(e) <= kRayTolerance; });
  };
  Vector3d plane_normal = Vector3d::Zero();
  double best = 0.0;
  for (std::size_t i = 0; i < dirs.size(); ++i) {
    for (std::size_t j = i + 1; j < dirs.size(); ++j) {
      const Vector3d c = dirs[i].cross(dirs[j]);
      const double n = c.norm();
      if (n < 1e-9) continue;
      if (n > best) {
        best = n;
        plane_normal = c / n;
      }
      for (const double sign : {1.0, -1.0}) {
        const Vector3d r = sign * c / n;
        if (feasible(r)) rays.push_back(r);
      }
    }
  }
  if (best == 0.0) return false;  // collinear edges: not a surface vertex
  const bool coplanar = std::all_of(dirs.begin(), dirs.end(),
                                    [&](const Vector3d& e) { return std::abs(e.dot(plane_normal)) <= kRayTolerance; });
  if (!coplanar) return true;  // edges span space: the cone is pointed, spanned by these rays
  // Flat vertex: the cone holds the line of the normal, and more unless the edges surround it.
  for (const Vector3d& e : dirs) {
    const Vector3d w = plane_normal.cross(e).normalized();
    if (feasible(w) || feasible(-w)) return false;
  }
  rays = {plane_normal, -plane_normal};
  return true;
}

// Same for an edge: u is perpendicular to the edge and u . t <= 0 for the in-plane direction t
// of every incident triangle (perpendicular to the edge, into the triangle).
bool edgeNormalConeRays(const Vector3d& along, const std::vector<Vector3d>& into, std::vector<Vector3d>& rays) {
  rays.clear();
  auto feasible = [&](const Vector3d& r) {
    return std::all_of(into.begin(), into.end(), [&](const Vector3d& t) { return r.dot(t) <= kRayTolerance; });
  };
  bool opposite = false;
  for (const Vector3d& t : into) {
    const Vector3d c = along.cross(t).normalized();
    const bool plus = feasible(c);
    const bool minus = feasible(-c);
    if (plus) rays.push_back(c);
    if (minus) rays.push_back(-c);
    opposite = opposite || (plus && minus);
  }
  if (!opposite) return true;  // a wedge narrower than pi (or {0})
  // Two opposite rays: a line (flat edge) unless a half-plane is feasible (an open rim).
  for (const Vector3d& t : into) {
    if (feasible(-t)) return false;
  }
  return true;
}

// Per vertex, the spanning rays of its exact normal cone, computed once (state 1) or found
// unbounded (state 0); state -1 not computed yet.
struct VertexConeCache {
  std::vector<signed char> state;
  std::vector<std::vector<Vector3d>> rays;
};

// Cone (or double cone) around the exact normal cones of triangle t's face, edges and
// vertices; full when they do not fit in one of half angle below pi/2.
Cone exactFeatureCone(const TriMesh& mesh, int t, VertexConeCache& cache) {
  const auto& tri = mesh.triangle(t);
  const Vector3d n = mesh.faceNormal(t);
  std::vector<std::vector<Vector3d>> sets{{n}};
  std::vector<Vector3d> dirs;
  std::vector<Vector3d> rays;
  std::vector<int> ring;
  for (int k = 0; k < 3; ++k) {
    const int v = tri[k];
    const auto vi = static_cast<std::size_t>(v);
    if (cache.state[vi] < 0) {
      ring.clear();
      for (int s : mesh.vertexTriangles(v)) {
        for (int m = 0; m < 3; ++m) {
          if (mesh.triangle(s)[m] != v) ring.push_back(mesh.triangle(s)[m]);
        }
      }
      std::sort(ring.begin(), ring.end());
      ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
      dirs.clear();
      for (int w : ring) dirs.push_back((mesh.vertex(w) - mesh.vertex(v)).normalized());
      cache.state[vi] = vertexNormalConeRays(dirs, cache.rays[vi]) ? 1 : 0;
    }
    if (cache.state[vi] == 0) return {n, kPi};
    sets.push_back(cache.rays[vi]);
    const int e = mesh.triangleEdge(t, k);
    const auto ev = mesh.edgeVertices(e);
    const Vector3d p0 = mesh.vertex(ev[0]);
    const Vector3d along = (mesh.vertex(ev[1]) - p0).normalized();
    dirs.clear();
    for (int s : mesh.edgeTriangles(e)) {
      for (int m = 0; m < 3; ++m) {
        const int w = mesh.triangle(s)[m];
        if (w == ev[0] || w == ev[1]) continue;
        const Vector3d d = mesh.vertex(w) - p0;
        dirs.push_back((d - d.dot(along) * along).normalized());
      }
    }
    if (!edgeNormalConeRays(along, dirs, rays)) return {n, kPi};
    sets.push_back(rays);
  }
  // One-sided: every ray in one cap narrower than pi/2 (a convex cap holds each feature's cone).
  Cone one{n, 0.0};
  for (const auto& set : sets) {
    for (const Vector3d& r : set) one = mergeOneSided(one, {r, 0.0});
  }
  if (one.half_angle + kConeSlack_rad < 0.5 * kPi) return one;
  // Double-sided: each feature's rays all on one side of the face plane; turned to the face
  // normal's side, all in one cap narrower than pi/2 (a line feature contributes either ray).
  Cone two{n, 0.0, true};
  for (const auto& set : sets) {
    const bool line = set.size() == 2 && set[0].dot(set[1]) < -1.0 + 1e-12;
    bool up = true;
    bool down = true;
    for (const Vector3d& r : set) {
      up = up && r.dot(n) > kRayTolerance;
      down = down && r.dot(n) < -kRayTolerance;
    }
    if (line) {
      const Vector3d r = set[0].dot(n) >= 0.0 ? set[0] : set[1];
      if (std::abs(r.dot(n)) <= kRayTolerance) return {n, kPi};
      two = mergeOneSided(two, {r, 0.0});
      two.two_sided = true;
      continue;
    }
    if (!up && !down && !set.empty()) return {n, kPi};
    for (const Vector3d& r : set) {
      two = mergeOneSided(two, {up ? r : Vector3d(-r), 0.0});
      two.two_sided = true;
    }
  }
  return fullIfWide(two);
}

void setConeTrig(SnchNode& node) noexcept {
  const double open = node.cone_half_angle_rad + kConeSlack_rad;
  node.cone_cos = open < kPi ? std::cos(open) : -1.0;
  node.cone_sin = open < kPi ? std::sin(open) : 0.0;
}

// One triangle during the build: its vertex box, centroid and id.
struct BuildPrim {
  Vector3d lo;
  Vector3d hi;
  Vector3d centroid;
  int triangle;
};

// Top-down build into preallocated nodes: a range of n triangles becomes a subtree of exactly
// 2n - 1 nodes (median splits, one triangle per leaf) stored depth first from its root's id, so
// every subtree's ids are known before it is built and subtrees can be built on separate
// threads with the same result as on one.
struct Builder {
  const TriMesh& mesh;
  const std::vector<Cone>& leaf_cone;
  std::vector<BuildPrim>& prims;
  std::vector<SnchNode>& nodes;
  int parallel_depth = 0;  // subtrees above this depth split their left half onto a new thread

  void build(int begin, int end, int id, int depth) {
    // Bounding box of the vertices (the union of the triangles' boxes), then the sphere around
    // its centre through the farthest vertex.
    Vector3d lo = Vector3d::Constant(std::numeric_limits<double>::infinity());
    Vector3d hi = -lo;
    for (int i = begin; i < end; ++i) {
      const BuildPrim& p = prims[static_cast<std::size_t>(i)];
      lo = lo.cwiseMin(p.lo);
      hi = hi.cwiseMax(p.hi);
    }
    const Vector3d c = 0.5 * (lo + hi);
    double r_sq = 0.0;
    for (int i = begin; i < end; ++i) {
      const auto& t = mesh.triangle(prims[static_cast<std::size_t>(i)].triangle);
      for (int k = 0; k < 3; ++k) r_sq = std::max(r_sq, (mesh.vertex(t[k]) - c).squaredNorm());
    }
    SnchNode& node = nodes[static_cast<std::size_t>(id)];
    node.centre_m = c;
    node.radius_m = std::sqrt(r_sq) * (1.0 + 1e-12) + 1e-15;
    // Half extents grown like the radius, so rounding in the query never cuts a vertex off.
    node.box_half_m = (0.5 * (hi - lo)).cwiseMax(Vector3d::Zero()) * (1.0 + 1e-12) + Vector3d::Constant(1e-15);
    if (end - begin == 1) {
      const int t = prims[static_cast<std::size_t>(begin)].triangle;
      const Cone& cone = leaf_cone[static_cast<std::size_t>(t)];
      node.triangle = t;
      node.left = -1;
      node.right = -1;
      node.cone_axis = cone.axis;
      node.cone_half_angle_rad = cone.half_angle;
      node.cone_two_sided = cone.two_sided;
      setConeTrig(node);
      return;
    }
    // Median split along the longest extent of the centroids.
    Vector3d clo = Vector3d::Constant(std::numeric_limits<double>::infinity());
    Vector3d chi = -clo;
    for (int i = begin; i < end; ++i) {
      clo = clo.cwiseMin(prims[static_cast<std::size_t>(i)].centroid);
      chi = chi.cwiseMax(prims[static_cast<std::size_t>(i)].centroid);
    }
    int axis = 0;
    (chi - clo).maxCoeff(&axis);
    const int mid = begin + (end - begin) / 2;
    std::nth_element(prims.begin() + begin, prims.begin() + mid, prims.begin() + end,
                     [axis](const BuildPrim& x, const BuildPrim& y) {
                       return x.centroid[axis] < y.centroid[axis] ||
                              (x.centroid[axis] == y.centroid[axis] && x.triangle < y.triangle);
                     });
    const int left = id + 1;
    const int right = id + 2 * (mid - begin);
    if (depth < parallel_depth) {
      std::thread helper([&] { build(begin, mid, left, depth + 1); });
      build(mid, end, right, depth + 1);
      helper.join();
    } else {
      build(begin, mid, left, depth + 1);
      build(mid, end, right, depth + 1);
    }
    const SnchNode& l = nodes[static_cast<std::size_t>(left)];
    const SnchNode& rn = nodes[static_cast<std::size_t>(right)];
    const Cone merged = mergeCones({l.cone_axis, l.cone_half_angle_rad, l.cone_two_sided},
                                   {rn.cone_axis, rn.cone_half_angle_rad, rn.cone_two_sided});
    node.left = left;
    node.right = right;
    node.triangle = -1;
    node.cone_axis = merged.axis;
    node.cone_half_angle_rad = merged.half_angle;
    node.cone_two_sided = merged.two_sided;
    setConeTrig(node);
  }
};

// Runs body(i) for i in [0, n) on `threads` threads (contiguous blocks; each i is independent).
template <class Body>
void parallelFor(int n, int threads, const Body& body) {
  if (threads <= 1 || n < 4096) {
    for (int i = 0; i < n; ++i) body(i);
    return;
  }
  std::vector<std::thread> pool;
  for (int k = 1; k < threads; ++k) {
    pool.emplace_back([&, k] {
      for (int i = static_cast<int>(static_cast<long>(n) * k / threads);
           i < static_cast<int>(static_cast<long>(n) * (k + 1) / threads); ++i) {
        body(i);
      }
    });
  }
  for (int i = 0; i < static_cast<int>(static_cast<long>(n) / threads); ++i) body(i);
  for (std::thread& t : pool) t.join();
}

// Adds direction n to one-sided cone `c`: nothing when n already lies in it (one dot product;
// a rounding-level miss is far inside the query's kConeSlack_rad), else the tight merge.
void addNormal(Cone& c, double& cos_half, const Vector3d& n) noexcept {
  if (c.half_angle >= kPi || n.dot(c.axis) >= cos_half) return;
  c = mergeOneSided(c, {n, 0.0});
  cos_half = c.half_angle < kPi ? std::cos(c.half_angle) : -1.0;
}

// SnchTree::convex: closed (every edge has exactly two triangles) and every vertex on or
// behind every face plane within kConvexTolerance x the box diagonal. Every locally convex
// edge first (O(edges)): that rejects the usual non-convex mesh at once.
bool isClosedConvex(const TriMesh& mesh) {
  const int nt = mesh.numTriangles();
  const int nv = mesh.numVertices();
  if (nt < 4 || static_cast<long>(nt) * nv > kConvexCheckMaxWork) return false;
  Vector3d lo = mesh.vertex(0);
  Vector3d hi = lo;
  for (int v = 1; v < nv; ++v) {
    lo = lo.cwiseMin(mesh.vertex(v));
    hi = hi.cwiseMax(mesh.vertex(v));
  }
  const double tol = kConvexTolerance * (hi - lo).norm();
  const auto inFront = [&](int t, int v) {
    return mesh.faceNormal(t).dot(mesh.vertex(v) - mesh.vertex(mesh.triangle(t)[0])) > tol;
  };
  for (int e = 0; e < mesh.numEdges(); ++e) {
    const auto tris = mesh.edgeTriangles(e);
    if (tris.size() != 2) return false;
    for (int k = 0; k < 3; ++k) {
      if (inFront(tris[0], mesh.triangle(tris[1])[k]) || inFront(tris[1], mesh.triangle(tris[0])[k])) return false;
    }
  }
  for (int t = 0; t < nt; ++t) {
    for (int v = 0; v < nv; ++v) {
      if (inFront(t, v)) return false;
    }
  }
  return true;
}

}  // namespace

// G6: normal-cone merge (reports/equations.md).
SnchTree buildSnchTree(const TriMesh& mesh) {
  SnchTree tree;
  const int nt = mesh.numTriangles();
  const int nv = mesh.numVertices();
  const int threads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1U, 2U));
  // Vertices on a boundary or non-manifold edge: their normal cone (the directions u with
  // u . e <= 0 for every edge e leaving the vertex) is not bounded by the one-ring normals. At a
  // boundary edge it reaches the in-plane direction away from the face (an open sheet's rim is
  // approached edge-on), so a triangle touching such a vertex gets a full cone.
  std::vector<char> irregular_vertex(static_cast<std::size_t>(nv), 0);
  for (int e = 0; e < mesh.numEdges(); ++e) {
    if (mesh.edgeTriangles(e).size() == 2) continue;
    for (int v : mesh.edgeVertices(e)) irregular_vertex[static_cast<std::size_t>(v)] = 1;
  }
  // Leaf cone: the face normal and the normals of the one-rings of its three vertices (so edge
  // and vertex minima are covered); full at an irregular vertex.
  std::vector<Cone> leaf_cone(static_cast<std::size_t>(nt));
  std::vector<BuildPrim> prims(static_cast<std::size_t>(nt));
  std::vector<char> void_cone(static_cast<std::size_t>(nt), 0);
  parallelFor(nt, threads, [&](int t) {
    const auto& tri = mesh.triangle(t);
    const Vector3d& v0 = mesh.vertex(tri[0]);
    const Vector3d& v1 = mesh.vertex(tri[1]);
    const Vector3d& v2 = mesh.vertex(tri[2]);
    prims[static_cast<std::size_t>(t)] = {v0.cwiseMin(v1).cwiseMin(v2), v0.cwiseMax(v1).cwiseMax(v2),
                                          (v0 + v1 + v2) / 3.0, t};
    Cone cone{mesh.faceNormal(t), 0.0};
    double cos_half = 1.0;
    for (int k = 0; k < 3 && cone.half_angle < kPi; ++k) {
      if (irregular_vertex[static_cast<std::size_t>(tri[k])] != 0) {
        cone.half_angle = kPi;
        break;
      }
      for (const int s : mesh.vertexTriangles(tri[k])) addNormal(cone, cos_half, mesh.faceNormal(s));
    }
    leaf_cone[static_cast<std::size_t>(t)] = cone;
    void_cone[static_cast<std::size_t>(t)] = cone.half_angle >= kPi ? 1 : 0;
  });
  // Where the one-ring bound is void (double-sided surfaces, whose one-rings hold opposite
  // normals; rims; thin parts), bound the features' exact normal cones instead.
  VertexConeCache vertex_cones{std::vector<signed char>(static_cast<std::size_t>(nv), -1),
                               std::vector<std::vector<Vector3d>>(static_cast<std::size_t>(nv))};
  for (int t = 0; t < nt; ++t) {
    if (void_cone[static_cast<std::size_t>(t)] != 0)
      leaf_cone[static_cast<std::size_t>(t)] = exactFeatureCone(mesh, t, vertex_cones);
  }
  tree.nodes.resize(static_cast<std::size_t>(2 * nt - 1));
  Builder b{mesh, leaf_cone, prims, tree.nodes, threads > 1 && nt >= 4096 ? 1 : 0};
  b.build(0, nt, 0, 0);
  tree.convex = isClosedConvex(mesh);
  if (tree.convex) {
    tree.vertex_graph = buildVertexGraph(mesh);
    tree.support_start_vertex = mesh.triangle(0)[0];
    tree.bracket = buildConvexBracket(mesh);
    tree.support_table = buildSupportTable(mesh, kSupportTableCells);
  }
  tree.leaf_of_triangle.assign(static_cast<std::size_t>(nt), -1);
  for (int i = 0; i < static_cast<int>(tree.nodes.size()); ++i) {
    const SnchNode& node = tree.nodes[static_cast<std::size_t>(i)];
    if (node.isLeaf()) tree.leaf_of_triangle[static_cast<std::size_t>(node.triangle)] = i;
  }
  return tree;
}

TriangleTriangleResult closestPointsInObjectFrame(const TriMesh& link_mesh, int tri_link, const TriMesh& object_mesh,
                                                  int tri_object, const Isometry3d& X_OL) noexcept {
  const auto& a = link_mesh.triangle(tri_link);
  const auto& b = object_mesh.triangle(tri_object);
  return closestPointsTriangleTriangle(X_OL * link_mesh.vertex(a[0]), X_OL * link_mesh.vertex(a[1]),
                                       X_OL * link_mesh.vertex(a[2]), object_mesh.vertex(b[0]),
                                       object_mesh.vertex(b[1]), object_mesh.vertex(b[2]));
}

Feature meshFeature(const TriMesh& mesh, int tri, const LocalFeature& f) noexcept {
  switch (f.kind) {
    case LocalFeature::Kind::kVertex:
      return {FeatureKind::kVertex, mesh.triangle(tri)[f.index]};
    case LocalFeature::Kind::kEdge:
      return {FeatureKind::kEdge, mesh.triangleEdge(tri, f.index)};
    case LocalFeature::Kind::kFace:
      break;
  }
  return {FeatureKind::kFace, tri};
}

namespace {

// evaluateTrianglePair with the link vertices in the object frame given by `link_vertex_O(v)`
// (X_OL * vertex, computed on the fly or read from a per-query cache: the same values).
// `pair_distance_m` receives the distance of the two triangles (a minimum or not).
// evaluatePair with the triangles' closest pair `r` already computed (the convex-link path
// prepares the object triangle once per leaf).
template <class LinkVertex>
bool evaluatePairResult(const TriMesh& link_mesh, const LinkVertex& link_vertex_O, int tri_link,
                        const TriMesh& object_mesh, int tri_object, const Isometry3d& X_OL, double cutoff_m,
                        const TriangleTriangleResult& r, LocalMinimum& out) noexcept {
  if (r.distance_m > cutoff_m) return false;
  const Feature fl = meshFeature(link_mesh, tri_link, r.feature_a);
  const Feature fo = meshFeature(object_mesh, tri_object, r.feature_b);
  const double d = r.distance_m;
  const double accept = d - kLocalMinimumTolerance_m;
  // (1) Local minimum over both feature neighbourhoods, the object's first: in one valve-scene
  // query (736 pairs within the cutoff) the link side rejected 86 pairs with 2,353 neighbour
  // tests and the object side 617 of the remaining 650, so testing the object side first skips
  // most link-side tests. Either order gives the same answer.
  if (d > 0.0) {
    for (int t : object_mesh.featureTriangles(fo)) {
      if (t == tri_object) continue;
      const auto& b = object_mesh.triangle(t);
      if (accept > 0.0 && squaredDistancePointTriangle(r.p, object_mesh.vertex(b[0]), object_mesh.vertex(b[1]),
                                                       object_mesh.vertex(b[2])) < accept * accept) {
        return false;
      }
    }
    for (int t : link_mesh.featureTriangles(fl)) {
      if (t == tri_link) continue;
      const auto& a = link_mesh.triangle(t);
      if (accept > 0.0 && squaredDistancePointTriangle(r.q, link_vertex_O(a[0]), link_vertex_O(a[1]),
                                                       link_vertex_O(a[2])) < accept * accept) {
        return false;
      }
    }
  }
  // (2) Seen from outside on both sides.
  const Vector3d n_o = object_mesh.featureNormal(fo);
  Vector3d u;
  if (d > 0.0) {
    u = (r.q - r.p) / d;
    const Vector3d n_l = X_OL.linear() * link_mesh.featureNormal(fl);
    if (u.dot(n_l) < -kOutsideCosineTolerance || -u.dot(n_o) < -kOutsideCosineTolerance) return false;
  } else {
    u = n_o.squaredNorm() > 0.0 ? Vector3d(-n_o) : Vector3d(-object_mesh.faceNormal(tri_object));
  }
  out.tri_link = tri_link;
  out.tri_object = tri_object;
  out.feature_link = fl;
  out.feature_object = fo;
  out.p_L = X_OL.inverse() * r.p;
  out.p_O = r.q;
  out.distance_m = d;
  out.u_W = u;
  out.previous_distance_m = std::numeric_limits<double>::quiet_NaN();
  return true;
}

template <class LinkVertex>
bool evaluatePair(const TriMesh& link_mesh, const LinkVertex& link_vertex_O, int tri_link, const TriMesh& object_mesh,
                  int tri_object, const Isometry3d& X_OL, double cutoff_m, LocalMinimum& out,
                  double& pair_distance_m) noexcept {
  const auto& ta = link_mesh.triangle(tri_link);
  const auto& tb = object_mesh.triangle(tri_object);
  const TriangleTriangleResult r =
      closestPointsTriangleTriangle(link_vertex_O(ta[0]), link_vertex_O(ta[1]), link_vertex_O(ta[2]),
                                    object_mesh.vertex(tb[0]), object_mesh.vertex(tb[1]), object_mesh.vertex(tb[2]));
  pair_distance_m = r.distance_m;
  return evaluatePairResult(link_mesh, link_vertex_O, tri_link, object_mesh, tri_object, X_OL, cutoff_m, r, out);
}

}  // namespace

// G5: angle-weighted pseudo-normal (reports/equations.md).
bool evaluateTrianglePair(const TriMesh& link_mesh, int tri_link, const TriMesh& object_mesh, int tri_object,
                          const Isometry3d& X_OL, double cutoff_m, LocalMinimum& out) noexcept {
  double pair_distance_m = 0.0;
  return evaluatePair(
      link_mesh, [&](int v) -> Vector3d { return X_OL * link_mesh.vertex(v); }, tri_link, object_mesh, tri_object, X_OL,
      cutoff_m, out, pair_distance_m);
}

std::size_t mergeDuplicateMinima(std::vector<LocalMinimum>& minima, std::size_t begin) noexcept {
  // The triangles close the key: the kept representative (its triangle pair, and u_W for a
  // touching pair, which comes from that triangle) does not depend on the order of discovery.
  auto key = [](const LocalMinimum& m) {
    return std::make_tuple(m.link, m.object, static_cast<int>(m.feature_link.kind), m.feature_link.index,
                           static_cast<int>(m.feature_object.kind), m.feature_object.index, m.distance_m, m.tri_link,
                           m.tri_object);
  };
  const auto first = minima.begin() + static_cast<std::ptrdiff_t>(begin);
  std::sort(first, minima.end(), [&](const LocalMinimum& a, const LocalMinimum& b) { return key(a) < key(b); });
  const auto last = std::unique(first, minima.end(),
                                [](const LocalMinimum& a, const LocalMinimum& b) { return sameFeaturePair(a, b); });
  minima.erase(last, minima.end());
  return minima.size();
}

namespace {

// Normal-cone tests of a node pair proven at least `gap_m` > 0 apart (every point pair under it
// is then separated, so a local minimum's direction u = (q - p)/|q - p| must lie in A's cone
// and -u in B's cone). Returns false when no local minimum can exist under the pair. All
// vectors in the object frame except where noted; `diff` = c_B - c_A.
bool conesAdmit(const SnchNode& a, const Vector3d& a_axis, const SnchNode& b, const Eigen::Matrix3d& R_OL,
                const Vector3d& diff, double dist, double gap_m) noexcept {
  const bool a_bounded = a.cone_cos > -1.0;
  const bool b_bounded = b.cone_cos > -1.0;
  if (!a_bounded && !b_bounded) return true;
  const Vector3d& b_axis = b.cone_axis;
  // (1) u in cone A and -u in cone B: angle(a_A, -a_B) <= alpha_A + alpha_B (with the slack);
  // with a double cone on either side, the angle between the axes' lines.
  if (a_bounded && b_bounded && a.cone_half_angle_rad + b.cone_half_angle_rad + 2.0 * kConeSlack_rad < kPi) {
    const double cos_sum = a.cone_cos * b.cone_cos - a.cone_sin * b.cone_sin;
    const double c = -a_axis.dot(b_axis);
    if ((a.cone_two_sided || b.cone_two_sided ? std::abs(c) : c) < cos_sum) return false;
  }
  // (2) Spanning cone of the two spheres (Johnson & Cohen): every direction from sphere A to
  // sphere B lies within sigma = asin((r_A + r_B)/D) of s = diff/D.
  const double rsum = a.radius_m + b.radius_m;
  if (dist > rsum) {
    const double sin_sigma = rsum / dist;
    const double cos_sigma = std::sqrt(std::max(0.0, 1.0 - sin_sigma * sin_sigma));
    // cos(alpha + sigma), valid while alpha + sigma < pi (sigma <= pi/2).
    if (a_bounded && (a.cone_cos >= 0.0 || sin_sigma < a.cone_sin)) {
      const double c = a_axis.dot(diff);
      if ((a.cone_two_sided ? std::abs(c) : c) < dist * (a.cone_cos * cos_sigma - a.cone_sin * sin_sigma)) return false;
    }
    if (b_bounded && (b.cone_cos >= 0.0 || sin_sigma < b.cone_sin)) {
      const double c = -b_axis.dot(diff);
      if ((b.cone_two_sided ? std::abs(c) : c) < dist * (b.cone_cos * cos_sigma - b.cone_sin * sin_sigma)) return false;
    }
  }
  // (3) Support along the axes: (q - p) . a_A >= cos(alpha_A) |q - p| >= cos(alpha_A) gap, and
  // the largest (q - p) . a_A over the two boxes is diff . a_A plus both boxes' support.
  if (a.cone_cos > 0.0 && !a.cone_two_sided) {
    const double reach =
        a_axis.dot(diff) + a_axis.cwiseAbs().dot(b.box_half_m) + a.cone_axis.cwiseAbs().dot(a.box_half_m);
    if (reach < a.cone_cos * gap_m) return false;
  }
  if (b.cone_cos > 0.0 && !b.cone_two_sided) {
    const double reach = -b_axis.dot(diff) + b_axis.cwiseAbs().dot(b.box_half_m) +
                         (R_OL.transpose() * b_axis).cwiseAbs().dot(a.box_half_m);
    if (reach < b.cone_cos * gap_m) return false;
  }
  // Double cones: |(q - p) . a| >= cos(alpha) gap; the boxes bound (q - p) . a on both sides.
  if (a.cone_cos > 0.0 && a.cone_two_sided) {
    const double extent = a_axis.cwiseAbs().dot(b.box_half_m) + a.cone_axis.cwiseAbs().dot(a.box_half_m);
    if (std::abs(a_axis.dot(diff)) + extent < a.cone_cos * gap_m) return false;
  }
  if (b.cone_cos > 0.0 && b.cone_two_sided) {
    const double extent =
        b_axis.cwiseAbs().dot(b.box_half_m) + (R_OL.transpose() * b_axis).cwiseAbs().dot(a.box_half_m);
    if (std::abs(b_axis.dot(diff)) + extent < b.cone_cos * gap_m) return false;
  }

  return true;
}

// Lower bound on the distance between triangles A and B (same frame) from separating axes: the
// two face normals, then the six in-plane edge normals (a projection on an axis never lengthens
// a distance, so the gap along any axis divided by its length bounds the distance). Returns 0
// when no axis separates them. Axes are left unnormalised; the comparison is done squared.
// With `faces_only`, the two face normals only (a weaker bound, for the convex-link path).
// Stops at the first axis whose bound exceeds `stop_m` and returns that bound (the caller only
// needs to know that the pair is farther than `stop_m`; on the valve scene about a third of the
// leaf pairs are).
double triangleGapLowerBound(const Vector3d (&a)[3], const Vector3d& n_a, const Vector3d (&b)[3], const Vector3d& n_b,
                             double stop_m, bool faces_only = false) noexcept {
  // Scalar code on purpose: this runs on every leaf pair, and the Eigen expressions with
  // initializer-list min/max compiled to about twice the instructions.
  const double ax[3] = {a[0].x(), a[1].x(), a[2].x()};
  const double ay[3] = {a[0].y(), a[1].y(), a[2].y()};
  const double az[3] = {a[0].z(), a[1].z(), a[2].z()};
  const double bx[3] = {b[0].x(), b[1].x(), b[2].x()};
  const double by[3] = {b[0].y(), b[1].y(), b[2].y()};
  const double bz[3] = {b[0].z(), b[1].z(), b[2].z()};
  double best_sq = 0.0;
  const double stop_sq = stop_m * stop_m;
  // Returns true once the bound exceeds stop_m.
  const auto consider = [&](double x, double y, double z) noexcept {
    const double a0 = ax[0] * x + ay[0] * y + az[0] * z;
    const double a1 = ax[1] * x + ay[1] * y + az[1] * z;
    const double a2 = ax[2] * x + ay[2] * y + az[2] * z;
    const double b0 = bx[0] * x + by[0] * y + bz[0] * z;
    const double b1 = bx[1] * x + by[1] * y + bz[1] * z;
    const double b2 = bx[2] * x + by[2] * y + bz[2] * z;
    const double a_lo = std::min(a0, std::min(a1, a2));
    const double a_hi = std::max(a0, std::max(a1, a2));
    const double b_lo = std::min(b0, std::min(b1, b2));
    const double b_hi = std::max(b0, std::max(b1, b2));
    const double gap = std::max(b_lo - a_hi, a_lo - b_hi);
    if (gap > 0.0) {
      const double len_sq = x * x + y * y + z * z;
      if (gap * gap > best_sq * len_sq) best_sq = gap * gap / len_sq;
    }
    return best_sq > stop_sq;
  };
  // In-plane normal n x (v1 - v0) of one edge.
  const auto edgeAxis = [&](const Vector3d& n, const Vector3d& v0, const Vector3d& v1) noexcept {
    const double ex = v1.x() - v0.x();
    const double ey = v1.y() - v0.y();
    const double ez = v1.z() - v0.z();
    return consider(n.y() * ez - n.z() * ey, n.z() * ex - n.x() * ez, n.x() * ey - n.y() * ex);
  };
  if (consider(n_a.x(), n_a.y(), n_a.z()) || consider(n_b.x(), n_b.y(), n_b.z()) || faces_only) {
    return std::sqrt(best_sq);
  }
  for (int k = 0; k < 3; ++k) {
    if (edgeAxis(n_a, a[k], a[(k + 1) % 3]) || edgeAxis(n_b, b[k], b[(k + 1) % 3])) break;
  }
  return std::sqrt(best_sq);
}

// The support tests of conesAdmit on the two triangles themselves (vertices in the object
// frame): over p in A and q in B, (q - p) . a_A must reach cos(alpha_A) gap (either sign for a
// double cone), and (p - q) . a_B likewise.
bool leafConesAdmit(const SnchNode& a, const Vector3d& a_axis, const SnchNode& b, const Vector3d (&va)[3],
                    const Vector3d (&vb)[3], double gap_m) noexcept {
  auto span = [&](const Vector3d& axis, double& lo, double& hi) {  // of (q - p) . axis
    const double p0 = va[0].dot(axis), p1 = va[1].dot(axis), p2 = va[2].dot(axis);
    const double q0 = vb[0].dot(axis), q1 = vb[1].dot(axis), q2 = vb[2].dot(axis);
    hi = std::max({q0, q1, q2}) - std::min({p0, p1, p2});
    lo = std::min({q0, q1, q2}) - std::max({p0, p1, p2});
  };
  double lo = 0.0;
  double hi = 0.0;
  if (a.cone_cos > 0.0) {
    span(a_axis, lo, hi);
    const double reach = a.cone_two_sided ? std::max(hi, -lo) : hi;
    if (reach < a.cone_cos * gap_m) return false;
  }
  if (b.cone_cos > 0.0) {
    span(b.cone_axis, lo, hi);
    const double reach = b.cone_two_sided ? std::max(hi, -lo) : -lo;
    if (reach < b.cone_cos * gap_m) return false;
  }
  return true;
}

// leafConesAdmit with [qb_lo, qb_hi] = the range of q . a_B over B given (the convex-link path
// computes it once per object leaf): the same tests.
bool leafConesAdmit(const SnchNode& a, const Vector3d& a_axis, const SnchNode& b, const Vector3d (&va)[3],
                    const Vector3d (&vb)[3], double qb_lo, double qb_hi, double gap_m) noexcept {
  if (a.cone_cos > 0.0) {
    const double p0 = va[0].dot(a_axis), p1 = va[1].dot(a_axis), p2 = va[2].dot(a_axis);
    const double q0 = vb[0].dot(a_axis), q1 = vb[1].dot(a_axis), q2 = vb[2].dot(a_axis);
    const double hi = std::max({q0, q1, q2}) - std::min({p0, p1, p2});
    const double lo = std::min({q0, q1, q2}) - std::max({p0, p1, p2});
    const double reach = a.cone_two_sided ? std::max(hi, -lo) : hi;
    if (reach < a.cone_cos * gap_m) return false;
  }
  if (b.cone_cos > 0.0) {
    const double p0 = va[0].dot(b.cone_axis), p1 = va[1].dot(b.cone_axis), p2 = va[2].dot(b.cone_axis);
    const double hi = qb_hi - std::min({p0, p1, p2});
    const double lo = qb_lo - std::max({p0, p1, p2});
    const double reach = b.cone_two_sided ? std::max(hi, -lo) : -lo;
    if (reach < b.cone_cos * gap_m) return false;
  }
  return true;
}

// Bumps a per-element stamp counter; on wrap-around clears the stamps so no entry looks current.
std::uint32_t nextStamp(std::uint32_t& counter, std::vector<std::uint32_t>& a, std::vector<std::uint32_t>& b) noexcept {
  if (++counter == 0) {
    std::fill(a.begin(), a.end(), 0U);
    std::fill(b.begin(), b.end(), 0U);
    counter = 1;
  }
  return counter;
}

// querySnchPair for a convex link (SnchTree::convex): a traversal of the object tree alone
// against the whole link body. An object node is dropped when its sphere is farther than L
// from the body (GJK lower bound); at an object leaf B, GJK bounds B's distance to the body,
// which bounds the distance of every minimum on B (kConvexBoundSlack_m), and the link
// triangles that can pair with B are those reaching within that bound of B along the GJK axis:
// on a convex body the vertices above a level along an axis are connected in the vertex graph
// (from any vertex below the top some neighbour is strictly higher), so a search from the
// topmost vertex finds them all. Each candidate pair then goes through the same leaf tests and
// exact test as in the two-tree traversal.
void queryConvexLink(const SnchTree& link_tree, const TriMesh& link_mesh, const Isometry3d& X_OL,
                     const SnchTree& obj_tree, const TriMesh& obj_mesh, const Isometry3d& X_WO, double cutoff_m,
                     SnchQueryScratch& scratch, std::vector<LocalMinimum>& out, SnchQueryStats& st) {
  const Eigen::Matrix3d R_OL = X_OL.linear();
  const Eigen::Matrix3d abs_R_OL = R_OL.cwiseAbs();
  auto& vertex_O = scratch.link_vertex_O;
  const auto n_link_vertices = static_cast<std::size_t>(link_mesh.numVertices());
  const auto n_link_triangles = static_cast<std::size_t>(link_mesh.numTriangles());
  vertex_O.resize(n_link_vertices);
  // The link's vertices in the object frame, on first use: most link/object pairs end at the
  // roots or at the bracket bounds of the object's inner nodes and never read them.
  bool vertices_ready = false;
  const auto readyVertices = [&]() noexcept {
    if (vertices_ready) return;
    for (std::size_t v = 0; v < n_link_vertices; ++v) vertex_O[v] = X_OL * link_mesh.vertex(static_cast<int>(v));
    vertices_ready = true;
  };
  if (scratch.link_vertex_stamp.size() < n_link_vertices) scratch.link_vertex_stamp.resize(n_link_vertices, 0);
  if (scratch.link_vertex_height.size() < n_link_vertices) scratch.link_vertex_height.resize(n_link_vertices, 0.0);
  if (scratch.link_triangle_stamp.size() < n_link_triangles) scratch.link_triangle_stamp.resize(n_link_triangles, 0);
  // The bracket capsules in the object frame (SnchTree::bracket; GJK on the node centres when
  // it is not valid).
  const ConvexBracket& bracket = link_tree.bracket;
  const bool use_bracket = bracket.valid();
  const Vector3d bracket_a = X_OL * bracket.a_m;
  const Vector3d bracket_b = X_OL * bracket.b_m;
  const bool use_table = !link_tree.support_table.start_vertex.empty();
  // A vertex to start the support climb along `dir` (object frame) from: the table's vertex
  // for that direction, else `fallback`.
  const auto climbStart = [&](const Vector3d& dir, int fallback) noexcept {
    return use_table ? supportTableStart(link_tree.support_table, R_OL.transpose() * dir) : fallback;
  };
  // Support test of an object node's cone against the whole body (test 3 of conesAdmit with
  // the body in place of a link node): a minimum on the node has -u in its cone, so
  // (p - q) . a_B >= cos(alpha_B) |p - q| >= cos(alpha_B) gap for p on the body and q on the
  // node (|.| of it for a double cone); [q_lo, q_hi] bounds q . a_B over the node. The body's
  // extent along a_B: between the bracket's inner and outer capsules' extents (the segment
  // ends' extent -/+ the radius), exactly from the support vertices when the test's outcome
  // lies between the two.
  int cone_warm = link_tree.support_start_vertex;
  const auto objectConeAdmits = [&](const SnchNode& b, double q_lo, double q_hi, double gap) noexcept {
    const Vector3d& axis = b.cone_axis;
    const double need = b.cone_cos * gap;
    const double ea = bracket_a.dot(axis);
    const double eb = bracket_b.dot(axis);
    const double seg_hi = std::max(ea, eb);
    const double seg_lo = std::min(ea, eb);
    // Highest body point along the axis, p_hi in [seg_hi + inner, seg_hi + outer].
    bool admits = false;
    if (use_bracket && seg_hi + bracket.inner_radius_m - q_lo >= need) {
      admits = true;
    } else if (!use_bracket || seg_hi + bracket.outer_radius_m - q_lo >= need) {
      readyVertices();
      cone_warm = convexSupportVertex(link_tree.vertex_graph, vertex_O, axis, climbStart(axis, cone_warm));
      admits = vertex_O[static_cast<std::size_t>(cone_warm)].dot(axis) - q_lo >= need;
    }
    if (admits) return true;
    if (!b.cone_two_sided) return false;
    // Lowest, p_lo in [seg_lo - outer, seg_lo - inner].
    if (use_bracket && q_hi - seg_lo + bracket.inner_radius_m >= need) return true;
    if (use_bracket && q_hi - seg_lo + bracket.outer_radius_m < need) return false;
    readyVertices();
    const int low = convexSupportVertex(link_tree.vertex_graph, vertex_O, -axis, climbStart(-axis, cone_warm));
    const double p_lo = vertex_O[static_cast<std::size_t>(low)].dot(axis);
    return q_hi - p_lo >= need;
  };
  const SnchNode& root = link_tree.nodes[0];
  const Vector3d root_centre = X_OL * root.centre_m;
  const Vector3d root_half = abs_R_OL * root.box_half_m;
  // Support climbs start from the last support vertex found: the traversal is depth first, so
  // consecutive GJK runs are on nearby object nodes with nearby directions.
  int warm = link_tree.support_start_vertex;
  LocalMinimum m;
  auto& stack = scratch.stack;
  stack.clear();
  stack.emplace_back(0, 0);
  while (!stack.empty()) {
    // Each entry: (unused, object node).
    const int j = stack.back().second;
    stack.pop_back();
    ++st.node_pairs_visited;
    const SnchNode& b = obj_tree.nodes[static_cast<std::size_t>(j)];
    // The link root's sphere and box first (cheap), then GJK against the body.
    const Vector3d diff = b.centre_m - root_centre;
    const double reach = root.radius_m + b.radius_m + cutoff_m;
    if (diff.squaredNorm() > reach * reach || (diff.cwiseAbs() - b.box_half_m - root_half).maxCoeff() > cutoff_m) {
      ++st.pruned_by_distance;
      continue;
    }
    if (!b.isLeaf()) {
      // The node's sphere against the body: its centre's distance minus its radius.
      DistanceBounds db;
      if (use_bracket) {
        db = pointConvexBracketBounds(b.centre_m, bracket_a, bracket_b, bracket.outer_radius_m, bracket.inner_radius_m);
      } else {
        readyVertices();
        db = triangleConvexMeshDistanceBounds(b.centre_m, b.centre_m, b.centre_m, link_tree.vertex_graph, vertex_O,
                                              cutoff_m + b.radius_m, kConvexNodeTolerance_m, warm);
        ++st.convex_hull_tests;
      }
      if (db.lower_m - b.radius_m > cutoff_m) {
        ++st.pruned_by_distance;
        continue;
      }
      const double gap = db.lower_m - b.radius_m;
      if (gap > kConeTestMinGap_m && b.cone_cos > 0.0) {
        const double axis_centre = b.cone_axis.dot(b.centre_m);
        const double axis_extent = b.cone_axis.cwiseAbs().dot(b.box_half_m);
        if (!objectConeAdmits(b, axis_centre - axis_extent, axis_centre + axis_extent, gap)) {
          ++st.pruned_by_cone;
          continue;
        }
      }
      // Directions of the minima under the node: a minimum at q has u = (q - P(q)) / |q - P(q)|
      // with P the projection on the body (see kConvexBoundSlack_m). The residual map
      // F = I - P is firmly nonexpansive like P itself (|F x - F y|^2 <= (F x - F y) . (x - y),
      // which is P's firm nonexpansiveness rewritten), so |F x - F y| <= |x - y|: for q within
      // r_B of the centre c, |F(q) - F(c)| <= r_B, and u lies within asin(r_B / D) of u(c),
      // D = |c - P(c)| >= lower. u(c) lies within acos(lower / upper) of the bound's axis
      // (axis . (c - P(c)) >= lower). -u must lie in the node's cone.
      if (gap > kConeTestMinGap_m && b.cone_cos > -1.0 && b.radius_m < db.lower_m) {
        const double spread = std::asin(b.radius_m / db.lower_m) + std::acos(std::min(1.0, db.lower_m / db.upper_m));
        const double open = b.cone_half_angle_rad + kConeSlack_rad + spread;
        const double c = -db.axis.dot(b.cone_axis);
        if ((b.cone_two_sided && open < 0.5 * kPi && std::abs(c) < std::cos(open)) ||
            (!b.cone_two_sided && open < kPi && c < std::cos(open))) {
          ++st.pruned_by_cone;
          continue;
        }
      }
      stack.emplace_back(0, b.left);
      stack.emplace_back(0, b.right);
      continue;
    }
    const auto& tb = obj_mesh.triangle(b.triangle);
    const Vector3d vb[3] = {obj_mesh.vertex(tb[0]), obj_mesh.vertex(tb[1]), obj_mesh.vertex(tb[2])};
    // The triangle against the outer bracket capsule before GJK, along the axis n from the
    // segment's point s nearest the leaf's centre: s maximises n . x over the segment, so
    // n . (x - y) >= min_i n . (v_i - s) - outer for x on B and y on the body.
    if (use_bracket) {
      const DistanceBounds near =
          pointConvexBracketBounds(b.centre_m, bracket_a, bracket_b, bracket.outer_radius_m, bracket.inner_radius_m);
      if (near.lower_m > 0.0) {
        const Vector3d s = b.centre_m - (near.lower_m + bracket.outer_radius_m) * near.axis;
        const double lower = std::min({near.axis.dot(vb[0] - s), near.axis.dot(vb[1] - s), near.axis.dot(vb[2] - s)}) -
                             bracket.outer_radius_m;
        if (lower > cutoff_m + kConvexBoundSlack_m) {
          ++st.pruned_by_distance;
          continue;
        }
      }
    }
    // Then the triangle's exact closest pair with the bracket's segment: bounds and an axis
    // that serve like GJK's (DistanceBounds), GJK only when they do not separate.
    DistanceBounds db;
    if (use_bracket) {
      db = triangleConvexBracketBounds(vb[0], vb[1], vb[2], bracket_a, bracket_b, bracket.outer_radius_m,
                                       bracket.inner_radius_m);
    }
    if (!use_bracket || !(db.lower_m > 0.0) ||
        (db.lower_m <= cutoff_m + kConvexBoundSlack_m && db.upper_m > cutoff_m + kConvexBoundSlack_m)) {
      readyVertices();
      db = triangleConvexMeshDistanceBounds(vb[0], vb[1], vb[2], link_tree.vertex_graph, vertex_O,
                                            cutoff_m + kConvexBoundSlack_m, kConvexHullTolerance_m, warm);
      ++st.convex_hull_tests;
    }
    if (db.lower_m > cutoff_m + kConvexBoundSlack_m) {
      ++st.pruned_by_distance;
      continue;
    }
    // B's extent along its cone axis, for the cone tests below.
    double qb_lo = 0.0;
    double qb_hi = 0.0;
    if (b.cone_cos > 0.0) {
      const double v0 = b.cone_axis.dot(vb[0]);
      const double v1 = b.cone_axis.dot(vb[1]);
      const double v2 = b.cone_axis.dot(vb[2]);
      qb_lo = std::min({v0, v1, v2});
      qb_hi = std::max({v0, v1, v2});
    }
    if (db.lower_m > kConeTestMinGap_m && b.cone_cos > 0.0 && !objectConeAdmits(b, qb_lo, qb_hi, db.lower_m)) {
      ++st.pruned_by_cone;
      continue;
    }
    readyVertices();
    // B prepared for the exact tests on first use (most leaves reach none).
    PreparedTriangle prepared_b;
    bool b_prepared = false;
    double bound_m = db.upper_m;
    const Vector3d& axis = db.axis;
    const double b_min = std::min({axis.dot(vb[0]), axis.dot(vb[1]), axis.dot(vb[2])});
    // Link vertices at or above `level` along the axis: every triangle that can pair with B has
    // one (its top reaches b_min - limit >= level). The search is exact on a convex body; the
    // slack absorbs the convexity tolerance.
    const double level = b_min - std::min(cutoff_m, bound_m + kConvexBoundSlack_m) - kConvexBoundSlack_m;
    const std::uint32_t stamp = nextStamp(scratch.link_stamp, scratch.link_vertex_stamp, scratch.link_triangle_stamp);
    auto& frontier = scratch.link_frontier;
    frontier.clear();
    const int top = convexSupportVertex(link_tree.vertex_graph, vertex_O, axis, climbStart(axis, warm));
    warm = top;
    auto& height = scratch.link_vertex_height;
    height[static_cast<std::size_t>(top)] = vertex_O[static_cast<std::size_t>(top)].dot(axis);
    if (height[static_cast<std::size_t>(top)] >= level) {
      frontier.push_back(top);
      scratch.link_vertex_stamp[static_cast<std::size_t>(top)] = stamp;
    }
    // Over the vertex graph's edges (on a closed mesh a vertex's neighbours are the other
    // vertices of its triangles, each listed once); a vertex is stamped when first tested, so
    // one below the level is not tested again from its other neighbours.
    const VertexGraph& graph = link_tree.vertex_graph;
    for (std::size_t f = 0; f < frontier.size(); ++f) {
      const auto v = static_cast<std::size_t>(frontier[f]);
      for (int k = graph.offset[v]; k < graph.offset[v + 1]; ++k) {
        const int w = graph.neighbours[static_cast<std::size_t>(k)];
        const auto wk = static_cast<std::size_t>(w);
        if (scratch.link_vertex_stamp[wk] == stamp) continue;
        scratch.link_vertex_stamp[wk] = stamp;
        height[wk] = vertex_O[wk].dot(axis);
        if (height[wk] >= level) frontier.push_back(w);
      }
    }
    for (const int v : frontier) {
      for (const int tri_link : link_mesh.vertexTriangles(v)) {
        const auto tk = static_cast<std::size_t>(tri_link);
        if (scratch.link_triangle_stamp[tk] == stamp) continue;
        scratch.link_triangle_stamp[tk] = stamp;
        ++st.node_pairs_visited;
        const double limit = std::min(cutoff_m, bound_m + kConvexBoundSlack_m);
        const auto& ta = link_mesh.triangle(tri_link);
        // A lower bound on the pair's distance along the leaf's axis (the heights of the
        // triangle's vertices, all taken by the walk: each is in the frontier or a neighbour of a
        // frontier vertex): above the bound B's minima cannot be this far; else the cone tests
        // with it, the face-normal separating axes, then the exact test, which stops at `limit`
        // (a pair farther than the bound holds no minimum either).
        const double axis_gap =
            b_min - std::max({height[static_cast<std::size_t>(ta[0])], height[static_cast<std::size_t>(ta[1])],
                              height[static_cast<std::size_t>(ta[2])]});
        if (axis_gap > limit) {
          ++st.pruned_by_convex_bound;
          continue;
        }
        const Vector3d va[3] = {vertex_O[static_cast<std::size_t>(ta[0])], vertex_O[static_cast<std::size_t>(ta[1])],
                                vertex_O[static_cast<std::size_t>(ta[2])]};
        const SnchNode& a = link_tree.nodes[static_cast<std::size_t>(link_tree.leaf_of_triangle[tk])];
        const Vector3d a_axis = R_OL * a.cone_axis;
        const Vector3d leaf_diff = b.centre_m - X_OL * a.centre_m;
        const double leaf_dist = leaf_diff.norm();
        if (axis_gap > kConeTestMinGap_m && (!conesAdmit(a, a_axis, b, R_OL, leaf_diff, leaf_dist, axis_gap) ||
                                             !leafConesAdmit(a, a_axis, b, va, vb, qb_lo, qb_hi, axis_gap))) {
          ++st.pruned_by_cone;
          continue;
        }
        // The two face normals of the triangles' separating axes only: the six edge axes cost
        // more than the exact tests they saved on the valve scene (callgrind: 6.16 M with all
        // eight axes, 5.20 M with none, 5.44 M with the two; with none, the random-mesh test
        // gave 4x the exact tests of the two-tree traversal).
        const double tri_gap = triangleGapLowerBound(va, R_OL * link_mesh.faceNormal(tri_link), vb,
                                                     obj_mesh.faceNormal(b.triangle), limit, true);
        if (tri_gap > limit) {
          ++st.pruned_by_convex_bound;
          continue;
        }
        ++st.triangle_pairs_tested;
        if (!b_prepared) {
          prepared_b = prepareTriangle(vb[0], vb[1], vb[2]);
          b_prepared = true;
        }
        const TriangleTriangleResult r =
            closestPointsTriangleTriangle(prepareTriangle(va[0], va[1], va[2]), prepared_b);
        if (evaluatePairResult(
                link_mesh, [&](int w) -> const Vector3d& { return vertex_O[static_cast<std::size_t>(w)]; }, tri_link,
                obj_mesh, b.triangle, X_OL, limit, r, m)) {
          m.u_W = X_WO.linear() * m.u_W;
          out.push_back(m);
        }
        bound_m = std::min(bound_m, r.distance_m);
      }
    }
  }
}

}  // namespace

Feature capsuleFeature(double s) noexcept {
  if (s <= 0.0) return {FeatureKind::kVertex, 0};
  if (s >= 1.0) return {FeatureKind::kVertex, 1};
  return {FeatureKind::kEdge, 0};
}

CapsuleFeaturePair capsuleFeatureClosest(const Vector3d& a_O, const Vector3d& b_O, const TriMesh& mesh,
                                         const Feature& feature) noexcept {
  CapsuleFeaturePair r;
  r.holder = feature;
  switch (feature.kind) {
    case FeatureKind::kVertex:
      r.q_m = mesh.vertex(feature.index);
      r.s = closestSegmentParameter(a_O, b_O, r.q_m);
      r.on_segment_m = a_O + r.s * (b_O - a_O);
      break;
    case FeatureKind::kEdge: {
      const auto ev = mesh.edgeVertices(feature.index);
      const SegmentSegmentResult e = closestPointsSegmentSegment(a_O, b_O, mesh.vertex(ev[0]), mesh.vertex(ev[1]));
      r.s = e.s;
      r.on_segment_m = e.p;
      r.q_m = e.q;
      if (e.t <= 0.0) r.holder = {FeatureKind::kVertex, ev[0]};
      if (e.t >= 1.0) r.holder = {FeatureKind::kVertex, ev[1]};
      break;
    }
    case FeatureKind::kFace: {
      const auto& t = mesh.triangle(feature.index);
      const SegmentTriangleResult e = closestPointsSegmentTriangle(
          a_O, b_O, prepareTriangle(mesh.vertex(t[0]), mesh.vertex(t[1]), mesh.vertex(t[2])));
      r.s = e.s;
      r.on_segment_m = e.p;
      r.q_m = e.q;
      r.holder = meshFeature(mesh, feature.index, e.feature_t);
      break;
    }
  }
  r.distance_sq = (r.q_m - r.on_segment_m).squaredNorm();
  return r;
}

// G9: the capsule's distance and point from the segment's pair (reports/equations.md).
void capsuleMinimumFromPair(const CapsuleFeaturePair& pair, double radius_m, const Isometry3d& X_LO,
                            const TriMesh& object_mesh, int tri_object, const Feature& feature_object,
                            LocalMinimum& out) noexcept {
  const double d_s = std::sqrt(pair.distance_sq);
  Vector3d u;
  if (d_s > 0.0) {
    u = (pair.q_m - pair.on_segment_m) / d_s;
  } else {
    const Vector3d& n = object_mesh.featureNormal(feature_object);
    u = n.squaredNorm() > 0.0 ? Vector3d(-n) : Vector3d(-object_mesh.faceNormal(tri_object));
  }
  out.tri_link = -1;
  out.tri_object = tri_object;
  out.feature_link = capsuleFeature(pair.s);
  out.feature_object = feature_object;
  out.p_L = X_LO * (pair.on_segment_m + radius_m * u);
  out.p_O = pair.q_m;
  out.distance_m = std::max(0.0, d_s - radius_m);
  out.u_W = u;
  out.previous_distance_m = std::numeric_limits<double>::quiet_NaN();
}

void capsuleMinimumAtFeature(const Vector3d& a_O, const Vector3d& b_O, double radius_m, const Isometry3d& X_LO,
                             const TriMesh& object_mesh, int tri_object, const Feature& feature_object,
                             LocalMinimum& out) noexcept {
  capsuleMinimumFromPair(capsuleFeatureClosest(a_O, b_O, object_mesh, feature_object), radius_m, X_LO, object_mesh,
                         tri_object, feature_object, out);
}

namespace {

// evaluateCapsuleTriangle with the segment-triangle pair `r` already computed.
bool evaluateCapsulePair(const SegmentTriangleResult& r, const Vector3d& a_O, const Vector3d& b_O, double radius_m,
                         const Isometry3d& X_LO, const TriMesh& object_mesh, int tri_object, double cutoff_m,
                         LocalMinimum& out) noexcept {
  const double reach = cutoff_m + radius_m;
  if (!(r.distance_sq <= reach * reach)) return false;
  const Feature fo = meshFeature(object_mesh, tri_object, r.feature_t);
  if (r.distance_sq > 0.0) {
    const double d = std::sqrt(r.distance_sq);
    // Seen from outside, then the local minimum over f_q's neighbourhood (convexity: a
    // neighbour holds a point closer to the segment iff it holds one closer to s).
    if ((r.p - r.q).dot(object_mesh.featureNormal(fo)) < -kOutsideCosineTolerance * d) return false;
    const double accept = d - kLocalMinimumTolerance_m;
    if (accept > 0.0) {
      for (int t : object_mesh.featureTriangles(fo)) {
        if (t == tri_object) continue;
        const auto& b = object_mesh.triangle(t);
        if (squaredDistancePointTriangle(r.p, object_mesh.vertex(b[0]), object_mesh.vertex(b[1]),
                                         object_mesh.vertex(b[2])) < accept * accept) {
          return false;
        }
      }
    }
  }
  capsuleMinimumAtFeature(a_O, b_O, radius_m, X_LO, object_mesh, tri_object, fo, out);
  return out.distance_m <= cutoff_m;
}

SegmentTriangleResult segmentTriangleOfMesh(const Vector3d& a, const Vector3d& b, const TriMesh& mesh,
                                            int tri) noexcept {
  const auto& t = mesh.triangle(tri);
  return closestPointsSegmentTriangle(a, b, prepareTriangle(mesh.vertex(t[0]), mesh.vertex(t[1]), mesh.vertex(t[2])));
}

}  // namespace

// G9: local minimum of a capsule against a mesh (reports/equations.md).
bool evaluateCapsuleTriangle(const Vector3d& a_O, const Vector3d& b_O, double radius_m, const Isometry3d& X_LO,
                             const TriMesh& object_mesh, int tri_object, double cutoff_m, LocalMinimum& out) noexcept {
  return evaluateCapsulePair(segmentTriangleOfMesh(a_O, b_O, object_mesh, tri_object), a_O, b_O, radius_m, X_LO,
                             object_mesh, tri_object, cutoff_m, out);
}

namespace {

// The traversal of an object tree against a capsule's segment (querySnchCapsule), from given
// start nodes. With `front` set, every node where the traversal stops (pruned, or a leaf
// tested) is recorded with a lower bound on the distance from the segment to its triangles,
// minus `drift` (the bound then holds for the segment at the front's reference pose).
struct CapsuleTraversal {
  const SnchTree& tree;
  const TriMesh& mesh;
  Vector3d a;
  Vector3d b;
  double radius_m;
  double cutoff_m;
  Isometry3d X_LO;
  Eigen::Matrix3d R_WO;
  SnchQueryScratch& scratch;
  std::vector<LocalMinimum>& out;
  SnchQueryStats& st;
  CapsuleFront* front = nullptr;
  double drift_m = 0.0;

  Vector3d ab = b - a;
  double inv_ab_sq = ab.squaredNorm() > 0.0 ? 1.0 / ab.squaredNorm() : 0.0;
  Vector3d seg_lo = a.cwiseMin(b);
  Vector3d seg_hi = a.cwiseMax(b);
  // Every minimum lies within the cutoff of the capsule: within `reach` of its segment.
  double reach = cutoff_m + radius_m;

  void record(int node, double bound_m) const {
    if (front == nullptr) return;
    front->next_node.push_back(node);
    front->next_bound_m.push_back(bound_m - drift_m);
  }

  void run(int start) {
    auto& stack = scratch.stack;
    stack.clear();
    stack.emplace_back(0, start);
    LocalMinimum m;
    while (!stack.empty()) {
      const int j = stack.back().second;
      stack.pop_back();
      ++st.node_pairs_visited;
      const SnchNode& node = tree.nodes[static_cast<std::size_t>(j)];
      const Vector3d& c = node.centre_m;
      // The segment's point nearest the node's centre, exactly.
      const double t = std::clamp((c - a).dot(ab) * inv_ab_sq, 0.0, 1.0);
      const Vector3d w = c - (a + t * ab);
      const double dist_sq = w.squaredNorm();
      const double sphere_reach = node.radius_m + reach;
      if (dist_sq > sphere_reach * sphere_reach) {
        ++st.pruned_by_distance;
        if (front != nullptr) record(j, std::sqrt(dist_sq) - node.radius_m);
        continue;
      }
      // Distance lower bounds of the segment and the node: the sphere; the box along the
      // direction from the segment's nearest point to the centre (that point maximises the
      // direction over the segment); the box's own axes against the segment's extent.
      const double dist = std::sqrt(dist_sq);
      const Vector3d& h = node.box_half_m;
      double gap = dist - node.radius_m;
      if (dist > 0.0) gap = std::max(gap, dist - w.cwiseAbs().dot(h) / dist);
      gap = std::max(gap, std::max((seg_lo - c - h).maxCoeff(), (c - h - seg_hi).maxCoeff()));
      if (gap > reach) {
        ++st.pruned_by_distance;
        record(j, gap);
        continue;
      }
      // Normal cones, once the node is proven apart from the segment: a minimum at q has -u =
      // (s - q)/|s - q| in the node's cone, s the segment's point nearest q.
      if (gap > kConeTestMinGap_m && node.cone_cos > -1.0) {
        const Vector3d& axis = node.cone_axis;
        // Direction: s - q for q within r_B of c lies within asin(r_B / D) of -w (the map
        // x -> x - P(x), P the projection on the segment, is nonexpansive), D = |w| > r_B.
        if (node.radius_m < dist) {
          const double sin_sigma = node.radius_m / dist;
          const double cos_sigma = std::sqrt(std::max(0.0, 1.0 - sin_sigma * sin_sigma));
          const double c_axis = -w.dot(axis);
          bool pruned = false;
          if (node.cone_two_sided) {
            const double cos_open = node.cone_cos * cos_sigma - node.cone_sin * sin_sigma;
            pruned = node.cone_cos > 0.0 && cos_open > 0.0 && std::abs(c_axis) < dist * cos_open;
          } else if (node.cone_cos >= 0.0 || sin_sigma < node.cone_sin) {
            pruned = c_axis < dist * (node.cone_cos * cos_sigma - node.cone_sin * sin_sigma);
          }
          if (pruned) {
            ++st.pruned_by_cone;
            record(j, gap);
            continue;
          }
        }
        // Support: (s - q) . a_B >= cos(alpha_B) |s - q| >= cos(alpha_B) gap (either sign for a
        // double cone), against its extreme values over the segment and the box.
        if (node.cone_cos > 0.0) {
          const double ea = a.dot(axis);
          const double eb = b.dot(axis);
          const double centre = c.dot(axis);
          const double extent = axis.cwiseAbs().dot(h);
          const double hi = std::max(ea, eb) - (centre - extent);
          const double lo = std::min(ea, eb) - (centre + extent);
          if ((node.cone_two_sided ? std::max(hi, -lo) : hi) < node.cone_cos * gap) {
            ++st.pruned_by_cone;
            record(j, gap);
            continue;
          }
        }
      }
      if (node.isLeaf()) {
        ++st.triangle_pairs_tested;
        const SegmentTriangleResult r = segmentTriangleOfMesh(a, b, mesh, node.triangle);
        if (front != nullptr) record(j, std::sqrt(r.distance_sq));
        if (evaluateCapsulePair(r, a, b, radius_m, X_LO, mesh, node.triangle, cutoff_m, m)) {
          m.u_W = R_WO * m.u_W;
          out.push_back(m);
        }
        continue;
      }
      stack.emplace_back(0, node.left);
      stack.emplace_back(0, node.right);
    }
  }
};

}  // namespace

// §3.2.1: global search of a capsule link within the cutoff; G10: the node bounds of the traversal
// (CapsuleTraversal::run) against the segment (reports/equations.md).
void querySnchCapsule(const Capsule& capsule, const Isometry3d& X_WL, const SnchTree& obj_tree, const TriMesh& obj_mesh,
                      const Isometry3d& X_WO, double cutoff_m, SnchQueryScratch& scratch,
                      std::vector<LocalMinimum>& out, SnchQueryStats* stats) {
  SnchQueryStats local_stats;
  SnchQueryStats& st = stats != nullptr ? *stats : local_stats;
  st = {};
  const std::size_t begin = out.size();
  if (obj_tree.nodes.empty()) return;
  const Isometry3d X_OL = X_WO.inverse() * X_WL;
  CapsuleTraversal traversal{obj_tree,
                             obj_mesh,
                             X_OL * capsule.a_m,
                             X_OL * capsule.b_m,
                             capsule.radius_m,
                             cutoff_m,
                             X_OL.inverse(),
                             X_WO.linear(),
                             scratch,
                             out,
                             st};
  traversal.run(0);
  mergeDuplicateMinima(out, begin);
}

// G11: the front's bounds less the segment's drift (reports/equations.md).
void querySnchCapsuleCoherent(const Capsule& capsule, const Isometry3d& X_WL, const SnchTree& obj_tree,
                              const TriMesh& obj_mesh, const Isometry3d& X_WO, double cutoff_m,
                              SnchQueryScratch& scratch, CapsuleFront& front, std::vector<LocalMinimum>& out,
                              SnchQueryStats* stats) {
  SnchQueryStats local_stats;
  SnchQueryStats& st = stats != nullptr ? *stats : local_stats;
  st = {};
  const std::size_t begin = out.size();
  if (obj_tree.nodes.empty()) {
    front = {};
    return;
  }
  const Isometry3d X_OL = X_WO.inverse() * X_WL;
  CapsuleTraversal traversal{obj_tree,
                             obj_mesh,
                             X_OL * capsule.a_m,
                             X_OL * capsule.b_m,
                             capsule.radius_m,
                             cutoff_m,
                             X_OL.inverse(),
                             X_WO.linear(),
                             scratch,
                             out,
                             st,
                             &front};
  // Every point of the segment has moved by at most the larger move of its two ends (it is their
  // affine combination), so every distance lower bound of the reference pose holds now less that.
  const double drift = std::max((traversal.a - front.a_ref_m).norm(), (traversal.b - front.b_ref_m).norm());
  const bool rebuild = !front.valid || front.tree != &obj_tree || front.tree_nodes != obj_tree.nodes.size() ||
                       front.reach_m != traversal.reach || !(drift <= kCoherenceRebuildDrift_m) ||
                       front.node.size() > kCoherenceFrontGrowth * front.rebuilt_size + 64;
  front.next_node.clear();
  front.next_bound_m.clear();
  if (rebuild) {
    front.a_ref_m = traversal.a;
    front.b_ref_m = traversal.b;
    front.reach_m = traversal.reach;
    front.tree = &obj_tree;
    front.tree_nodes = obj_tree.nodes.size();
    traversal.drift_m = 0.0;
    traversal.run(0);
    front.rebuilt_size = front.next_node.size();
    ++st.coherence_rebuilds;
  } else {
    traversal.drift_m = drift;
    for (std::size_t i = 0; i < front.node.size(); ++i) {
      // A node proven farther than the reach at the reference pose by more than the drift is
      // still: kept without a test. Every other node is traversed as in a fresh query.
      if (front.bound_m[i] - drift > traversal.reach) {
        front.next_node.push_back(front.node[i]);
        front.next_bound_m.push_back(front.bound_m[i]);
        ++st.coherence_kept;
        continue;
      }
      traversal.run(front.node[i]);
    }
  }
  front.node.swap(front.next_node);
  front.bound_m.swap(front.next_bound_m);
  front.valid = true;
  mergeDuplicateMinima(out, begin);
}

// §3.2.1: global search within the cutoff, pruning and local descent of the minima; G7: spanning cone of two spheres
// (reports/equations.md).
void querySnchPair(const SnchTree& link_tree, const TriMesh& link_mesh, const Isometry3d& X_WL,
                   const SnchTree& obj_tree, const TriMesh& obj_mesh, const Isometry3d& X_WO, double cutoff_m,
                   SnchQueryScratch& scratch, std::vector<LocalMinimum>& out, SnchQueryStats* stats) {
  SnchQueryStats local_stats;
  SnchQueryStats& st = stats != nullptr ? *stats : local_stats;
  st = {};
  const std::size_t begin = out.size();
  if (link_tree.nodes.empty() || obj_tree.nodes.empty()) return;
  // Everything in the object frame: only the link's nodes need transforming.
  const Isometry3d X_OL = X_WO.inverse() * X_WL;
  if (link_tree.convex) {
    queryConvexLink(link_tree, link_mesh, X_OL, obj_tree, obj_mesh, X_WO, cutoff_m, scratch, out, st);
    mergeDuplicateMinima(out, begin);
    return;
  }
  const Eigen::Matrix3d R_OL = X_OL.linear();
  const Eigen::Matrix3d abs_R_OL = R_OL.cwiseAbs();
  // The link's nodes in the object frame, each when the traversal first reaches it (the link
  // tree is the small one, but most link/object pairs end within a few nodes of the roots).
  const std::size_t n_link_nodes = link_tree.nodes.size();
  if (scratch.link_node_O.size() < n_link_nodes) {
    scratch.link_node_O.resize(n_link_nodes);
    scratch.link_node_query.resize(n_link_nodes, 0);
  }
  if (++scratch.query == 0) {  // wrapped: every entry stale
    std::fill(scratch.link_node_query.begin(), scratch.link_node_query.end(), 0U);
    scratch.query = 1;
  }
  const std::uint32_t query = scratch.query;
  const auto link_node_O = [&](int i) -> const SnchQueryScratch::LinkNodeO& {
    const auto k = static_cast<std::size_t>(i);
    SnchQueryScratch::LinkNodeO& n = scratch.link_node_O[k];
    if (scratch.link_node_query[k] != query) {
      const SnchNode& a = link_tree.nodes[k];
      n.centre_m = X_OL * a.centre_m;
      n.axis = R_OL * a.cone_axis;
      n.box_half_m = abs_R_OL * a.box_half_m;
      scratch.link_node_query[k] = query;
    }
    return n;
  };
  // The link's vertices in the object frame, once, at the first leaf pair (every leaf pair
  // reads them; most link/object pairs are pruned before any leaf).
  auto& vertex_O = scratch.link_vertex_O;
  bool vertices_ready = false;
  const auto link_vertex_O = [&vertex_O](int v) -> const Vector3d& { return vertex_O[static_cast<std::size_t>(v)]; };
  auto& stack = scratch.stack;
  stack.clear();
  stack.emplace_back(0, 0);
  LocalMinimum m;
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    ++st.node_pairs_visited;
    const SnchNode& a = link_tree.nodes[static_cast<std::size_t>(i)];
    const SnchNode& b = obj_tree.nodes[static_cast<std::size_t>(j)];
    const SnchQueryScratch::LinkNodeO& a_O = link_node_O(i);
    const Vector3d diff = b.centre_m - a_O.centre_m;
    // Distance lower bounds: the spheres (squared first, no root for the far pairs), then the
    // separating gaps of the two boxes along the three object axes and the three link axes (any
    // unit direction bounds the distance).
    const double dist_sq = diff.squaredNorm();
    const double reach = a.radius_m + b.radius_m + cutoff_m;
    if (dist_sq > reach * reach) {
      ++st.pruned_by_distance;
      continue;
    }
    const double dist = std::sqrt(dist_sq);
    double gap = dist - a.radius_m - b.radius_m;
    // The object-axis gaps first (cheap); the link-axis gaps only for the pairs they leave.
    gap = std::max(gap, (diff.cwiseAbs() - b.box_half_m - a_O.box_half_m).maxCoeff());
    if (gap > cutoff_m) {
      ++st.pruned_by_distance;
      continue;
    }
    {
      const Vector3d& h = b.box_half_m;
      for (int k = 0; k < 3; ++k) {  // link axis k: the column k of R_OL
        const double centre_gap = std::abs(R_OL(0, k) * diff.x() + R_OL(1, k) * diff.y() + R_OL(2, k) * diff.z());
        const double b_extent = abs_R_OL(0, k) * h.x() + abs_R_OL(1, k) * h.y() + abs_R_OL(2, k) * h.z();
        gap = std::max(gap, centre_gap - a.box_half_m[k] - b_extent);
      }
    }
    if (gap > cutoff_m) {
      ++st.pruned_by_distance;
      continue;
    }
    if (gap > kConeTestMinGap_m && !conesAdmit(a, a_O.axis, b, R_OL, diff, dist, gap)) {
      ++st.pruned_by_cone;
      continue;
    }
    if (a.isLeaf() && b.isLeaf()) {
      if (!vertices_ready) {
        vertex_O.resize(static_cast<std::size_t>(link_mesh.numVertices()));
        for (int v = 0; v < link_mesh.numVertices(); ++v) {
          vertex_O[static_cast<std::size_t>(v)] = X_OL * link_mesh.vertex(v);
        }
        vertices_ready = true;
      }
      // Exact separating-axis bound of the two triangles before the closest-point computation.
      const auto& ta = link_mesh.triangle(a.triangle);
      const auto& tb = obj_mesh.triangle(b.triangle);
      const Vector3d va[3] = {link_vertex_O(ta[0]), link_vertex_O(ta[1]), link_vertex_O(ta[2])};
      const Vector3d vb[3] = {obj_mesh.vertex(tb[0]), obj_mesh.vertex(tb[1]), obj_mesh.vertex(tb[2])};
      const double tri_gap = triangleGapLowerBound(va, R_OL * link_mesh.faceNormal(a.triangle), vb,
                                                   obj_mesh.faceNormal(b.triangle), cutoff_m);
      if (tri_gap > cutoff_m) {
        ++st.pruned_by_distance;
        continue;
      }
      // The triangles' own gap often proves a separation that the boxes could not (a long link
      // strip's box overlaps the object leaves beside it): the cone tests then apply to the leaf
      // pair, with the larger of the two bounds.
      const double leaf_gap = std::max(gap, tri_gap);
      if (leaf_gap > kConeTestMinGap_m &&
          ((gap <= kConeTestMinGap_m && !conesAdmit(a, a_O.axis, b, R_OL, diff, dist, leaf_gap)) ||
           !leafConesAdmit(a, a_O.axis, b, va, vb, leaf_gap))) {
        ++st.pruned_by_cone;
        continue;
      }
      ++st.triangle_pairs_tested;
      double pair_distance_m = 0.0;
      if (evaluatePair(link_mesh, link_vertex_O, a.triangle, obj_mesh, b.triangle, X_OL, cutoff_m, m,
                       pair_distance_m)) {
        m.u_W = X_WO.linear() * m.u_W;
        out.push_back(m);
      }
    } else if (b.isLeaf() || (!a.isLeaf() && a.radius_m >= b.radius_m)) {
      stack.emplace_back(a.left, j);
      stack.emplace_back(a.right, j);
    } else {
      stack.emplace_back(i, b.left);
      stack.emplace_back(i, b.right);
    }
  }
  mergeDuplicateMinima(out, begin);
}

}  // namespace fullarm::haptics
