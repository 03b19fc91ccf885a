#include "fullarm/haptics/convex_distance.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "fullarm/haptics/geometry.hpp"

namespace fullarm::haptics {

using Eigen::Vector3d;

namespace {

constexpr int kMaxIterations = 64;

// GJK simplex: up to four points of the Minkowski difference.
struct Simplex {
  Vector3d w[4] = {Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero(), Vector3d::Zero()};
  int n = 0;
};

// Closest point to the origin of segment (a, b); keeps in `s` the vertices of the smallest
// face holding it.
Vector3d closestOnSegment(Simplex& s) noexcept {
  const Vector3d a = s.w[0];
  const Vector3d ab = s.w[1] - a;
  const double len_sq = ab.squaredNorm();
  const double t = len_sq > 0.0 ? -a.dot(ab) / len_sq : 0.0;
  if (t <= 0.0) {
    s.n = 1;
    return a;
  }
  if (t >= 1.0) {
    s.w[0] = s.w[1];
    s.n = 1;
    return s.w[0];
  }
  return a + t * ab;
}

// Closest point to the origin of triangle (a, b, c) by its Voronoi regions (Ericson, Real-Time
// Collision Detection, 5.1.5), with the face holding it.
Vector3d closestOnTriangle(const Vector3d& a, const Vector3d& b, const Vector3d& c, Simplex& face) noexcept {
  const Vector3d ab = b - a;
  const Vector3d ac = c - a;
  const double d1 = -ab.dot(a);
  const double d2 = -ac.dot(a);
  if (d1 <= 0.0 && d2 <= 0.0) {
    face.w[0] = a;
    face.n = 1;
    return a;
  }
  const double d3 = -ab.dot(b);
  const double d4 = -ac.dot(b);
  if (d3 >= 0.0 && d4 <= d3) {
    face.w[0] = b;
    face.n = 1;
    return b;
  }
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0) {
    face.w[0] = a;
    face.w[1] = b;
    face.n = 2;
    return a + (d1 / (d1 - d3)) * ab;
  }
  const double d5 = -ab.dot(c);
  const double d6 = -ac.dot(c);
  if (d6 >= 0.0 && d5 <= d6) {
    face.w[0] = c;
    face.n = 1;
    return c;
  }
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) {
    face.w[0] = a;
    face.w[1] = c;
    face.n = 2;
    return a + (d2 / (d2 - d6)) * ac;
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0) {
    face.w[0] = b;
    face.w[1] = c;
    face.n = 2;
    return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b);
  }
  const double denom = va + vb + vc;
  face.w[0] = a;
  face.w[1] = b;
  face.w[2] = c;
  face.n = 3;
  if (!(denom > 0.0)) return a;  // degenerate (collinear) triangle: its vertex a
  return a + (vb / denom) * ab + (vc / denom) * ac;
}

// Closest point to the origin of the simplex; reduces the simplex to the face holding it.
// Returns false when the origin lies in a full tetrahedron (the bodies intersect).
bool closestOnSimplex(Simplex& s, Vector3d& v) noexcept {
  switch (s.n) {
    case 1:
      v = s.w[0];
      return true;
    case 2:
      v = closestOnSegment(s);
      return true;
    case 3: {
      Simplex face;
      v = closestOnTriangle(s.w[0], s.w[1], s.w[2], face);
      s = face;
      return true;
    }
    default:
      break;
  }
  // Tetrahedron: the origin is inside when it lies on the inner side of all four faces.
  static constexpr int kFace[4][4] = {{0, 1, 2, 3}, {0, 1, 3, 2}, {0, 2, 3, 1}, {1, 2, 3, 0}};
  bool inside = true;
  double best = std::numeric_limits<double>::infinity();
  Simplex best_face;
  for (const auto& f : kFace) {
    const Vector3d& a = s.w[f[0]];
    const Vector3d n = (s.w[f[1]] - a).cross(s.w[f[2]] - a);
    const double side_origin = -n.dot(a);
    const double side_other = n.dot(s.w[f[3]] - a);
    // The origin is outside this face when it is on the side away from the fourth vertex (a
    // flat tetrahedron has no inside: every face is a candidate).
    if (side_origin * side_other > 0.0) continue;
    inside = false;
    Simplex face;
    const Vector3d c = closestOnTriangle(a, s.w[f[1]], s.w[f[2]], face);
    const double d = c.squaredNorm();
    if (d < best) {
      best = d;
      best_face = face;
      v = c;
    }
  }
  if (inside) return false;
  s = best_face;
  return true;
}

}  // namespace

VertexGraph buildVertexGraph(const TriMesh& mesh) {
  VertexGraph g;
  const auto n = static_cast<std::size_t>(mesh.numVertices());
  g.offset.assign(n + 1, 0);
  std::vector<int> ring;
  for (std::size_t v = 0; v < n; ++v) {
    ring.clear();
    for (const int t : mesh.vertexTriangles(static_cast<int>(v))) {
      for (const int w : mesh.triangle(t)) {
        if (w != static_cast<int>(v)) ring.push_back(w);
      }
    }
    std::sort(ring.begin(), ring.end());
    ring.erase(std::unique(ring.begin(), ring.end()), ring.end());
    g.neighbours.insert(g.neighbours.end(), ring.begin(), ring.end());
    g.offset[v + 1] = static_cast<int>(g.neighbours.size());
  }
  return g;
}

namespace {

// Cube-map cell of a direction: face 0-5 (+x, -x, +y, -y, +z, -z), then the two other
// coordinates over the largest one's magnitude, each in [-1, 1], binned.
int cubeCell(const Vector3d& d, int k) noexcept {
  const Vector3d a = d.cwiseAbs();
  int axis = 0;
  if (a.y() > a.x()) axis = 1;
  if (a.z() > a[axis]) axis = 2;
  const double m = a[axis];
  if (!(m > 0.0) || !std::isfinite(m)) return 0;
  const int face = 2 * axis + (d[axis] < 0.0 ? 1 : 0);
  const double u = d[(axis + 1) % 3] / m;
  const double w = d[(axis + 2) % 3] / m;
  const auto bin = [k](double x) { return std::clamp(static_cast<int>((x + 1.0) * 0.5 * k), 0, k - 1); };
  return (face * k + bin(u)) * k + bin(w);
}

}  // namespace

SupportTable buildSupportTable(const TriMesh& mesh, int cells_per_edge) {
  if (cells_per_edge < 1) throw std::invalid_argument("buildSupportTable: cells_per_edge must be at least 1");
  SupportTable table;
  table.cells_per_edge = cells_per_edge;
  const int k = cells_per_edge;
  table.start_vertex.assign(static_cast<std::size_t>(6 * k * k), mesh.numTriangles() > 0 ? mesh.triangle(0)[0] : 0);
  for (int face = 0; face < 6; ++face) {
    const int axis = face / 2;
    const double sign = face % 2 == 0 ? 1.0 : -1.0;
    for (int i = 0; i < k; ++i) {
      for (int j = 0; j < k; ++j) {
        Vector3d d = Vector3d::Zero();
        d[axis] = sign;
        d[(axis + 1) % 3] = -1.0 + (2.0 * i + 1.0) / k;
        d[(axis + 2) % 3] = -1.0 + (2.0 * j + 1.0) / k;
        double best = -std::numeric_limits<double>::infinity();
        int best_vertex = table.start_vertex[0];
        for (int t = 0; t < mesh.numTriangles(); ++t) {
          for (const int v : mesh.triangle(t)) {
            const double value = mesh.vertex(v).dot(d);
            if (value > best) {
              best = value;
              best_vertex = v;
            }
          }
        }
        table.start_vertex[static_cast<std::size_t>((face * k + i) * k + j)] = best_vertex;
      }
    }
  }
  return table;
}

int supportTableStart(const SupportTable& table, const Vector3d& direction) noexcept {
  return table.start_vertex[static_cast<std::size_t>(cubeCell(direction, table.cells_per_edge))];
}

ConvexBracket buildConvexBracket(const TriMesh& mesh) {
  ConvexBracket out;
  const int nv = mesh.numVertices();
  if (nv == 0 || mesh.numTriangles() == 0) return out;
  // Only vertices that some triangle uses belong to the body.
  std::vector<char> used(static_cast<std::size_t>(nv), 0);
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    for (const int v : mesh.triangle(t)) used[static_cast<std::size_t>(v)] = 1;
  }
  Vector3d mean = Vector3d::Zero();
  int count = 0;
  for (int v = 0; v < nv; ++v) {
    if (used[static_cast<std::size_t>(v)] == 0) continue;
    mean += mesh.vertex(v);
    ++count;
  }
  mean /= count;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int v = 0; v < nv; ++v) {
    if (used[static_cast<std::size_t>(v)] == 0) continue;
    const Vector3d d = mesh.vertex(v) - mean;
    cov += d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  const Vector3d axis = eig.eigenvectors().col(2).normalized();  // largest eigenvalue last
  double t_lo = std::numeric_limits<double>::infinity();
  double t_hi = -t_lo;
  double rho = 0.0;
  for (int v = 0; v < nv; ++v) {
    if (used[static_cast<std::size_t>(v)] == 0) continue;
    const Vector3d d = mesh.vertex(v) - mean;
    const double t = d.dot(axis);
    t_lo = std::min(t_lo, t);
    t_hi = std::max(t_hi, t);
    rho = std::max(rho, (d - t * axis).norm());
  }
  double s_lo = t_lo + rho;
  double s_hi = t_hi - rho;
  if (s_lo > s_hi) s_lo = s_hi = 0.5 * (t_lo + t_hi);
  out.a_m = mean + s_lo * axis;
  out.b_m = mean + s_hi * axis;
  const Vector3d ab = out.b_m - out.a_m;
  const double ab_sq = ab.squaredNorm();
  double outer = 0.0;
  for (int v = 0; v < nv; ++v) {
    if (used[static_cast<std::size_t>(v)] == 0) continue;
    const Vector3d d = mesh.vertex(v) - out.a_m;
    const double s = ab_sq > 0.0 ? std::clamp(d.dot(ab) / ab_sq, 0.0, 1.0) : 0.0;
    outer = std::max(outer, (d - s * ab).norm());
  }
  // Inner: the segment's ends behind every face plane by at least `inner` (the body is the
  // intersection of the face half-spaces, and a capsule lies in a half-space iff both ends of
  // its segment lie at least its radius inside it).
  double inner = std::numeric_limits<double>::infinity();
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    const Vector3d& n = mesh.faceNormal(t);
    const Vector3d& p = mesh.vertex(mesh.triangle(t)[0]);
    inner = std::min({inner, n.dot(p - out.a_m), n.dot(p - out.b_m)});
  }
  // Rounding margins: the outer capsule grown and the inner one shrunk by 1e-12 relative.
  out.outer_radius_m = outer * (1.0 + 1e-12) + 1e-15;
  out.inner_radius_m = inner * (1.0 - 1e-12) - 1e-15;
  return out;
}

namespace {
// Bounds that prune nothing: lower 0 (the node or triangle must be visited) and upper infinity.
DistanceBounds uninformativeBounds() noexcept {
  DistanceBounds out;
  out.upper_m = std::numeric_limits<double>::infinity();
  return out;
}
}  // namespace

DistanceBounds pointConvexBracketBounds(const Vector3d& c, const Vector3d& a, const Vector3d& b, double outer_radius_m,
                                        double inner_radius_m) noexcept {
  DistanceBounds out;
  const Vector3d ab = b - a;
  const Vector3d ac = c - a;
  const double ab_sq = ab.squaredNorm();
  if (!std::isfinite(ab_sq)) return uninformativeBounds();
  const double s = ab_sq > 0.0 ? std::clamp(ac.dot(ab) / ab_sq, 0.0, 1.0) : 0.0;
  const Vector3d d = ac - s * ab;
  const double dist = d.norm();
  if (!std::isfinite(dist)) return uninformativeBounds();
  out.upper_m = std::max(0.0, dist - inner_radius_m);
  out.lower_m = dist - outer_radius_m;
  if (out.lower_m > 0.0) {
    out.axis = d / dist;
  } else {
    out.lower_m = 0.0;
  }
  return out;
}

DistanceBounds triangleConvexBracketBounds(const Vector3d& t0, const Vector3d& t1, const Vector3d& t2,
                                           const Vector3d& a, const Vector3d& b, double outer_radius_m,
                                           double inner_radius_m) noexcept {
  DistanceBounds out;
  // Closest pair (q on the triangle, s on the segment).
  Vector3d q = t0;
  Vector3d s = a;
  double best_sq = std::numeric_limits<double>::infinity();
  const auto consider = [&](const Vector3d& on_triangle, const Vector3d& on_segment) {
    const double d_sq = (on_triangle - on_segment).squaredNorm();
    if (d_sq < best_sq) {
      best_sq = d_sq;
      q = on_triangle;
      s = on_segment;
    }
  };
  const Vector3d ab = b - a;
  if (!(std::isfinite(ab.squaredNorm()) && t0.allFinite() && t1.allFinite() && t2.allFinite())) {
    return uninformativeBounds();
  }
  const Vector3d n = (t1 - t0).cross(t2 - t0);
  const double side_a = n.dot(a - t0);
  const double side_b = n.dot(b - t0);
  bool crosses = false;
  if (ab.squaredNorm() > 0.0 && side_a * side_b <= 0.0 && side_a != side_b) {
    // The segment meets the triangle's plane at x: inside the triangle (same side of each edge
    // as the normal) means the two touch.
    const Vector3d x = a + (side_a / (side_a - side_b)) * ab;
    crosses = n.dot((t1 - t0).cross(x - t0)) >= 0.0 && n.dot((t2 - t1).cross(x - t1)) >= 0.0 &&
              n.dot((t0 - t2).cross(x - t2)) >= 0.0;
    if (crosses) consider(x, x);
  }
  if (!crosses) {
    consider(closestPointTriangle(a, t0, t1, t2).point, a);
    if (ab.squaredNorm() > 0.0) {
      consider(closestPointTriangle(b, t0, t1, t2).point, b);
      const Vector3d* v[3] = {&t0, &t1, &t2};
      for (int k = 0; k < 3; ++k) {
        const SegmentSegmentResult r = closestPointsSegmentSegment(a, b, *v[k], *v[(k + 1) % 3]);
        consider(r.q, r.p);
      }
    }
  }
  // NaN or infinite input (a NaN pose): no candidate compared below infinity. Say nothing
  // rather than "far apart", which would prune silently.
  if (!std::isfinite(best_sq)) return uninformativeBounds();
  const double dist = std::sqrt(best_sq);
  out.upper_m = std::max(0.0, dist - inner_radius_m);
  out.lower_m = dist - outer_radius_m;
  if (out.lower_m > 0.0) {
    out.axis = (q - s) / dist;
  } else {
    out.lower_m = 0.0;
  }
  return out;
}

int convexSupportVertex(const VertexGraph& graph, std::span<const Vector3d> vertices, const Vector3d& direction,
                        int start) noexcept {
  int best = start;
  double best_value = vertices[static_cast<std::size_t>(start)].dot(direction);
  // Each step moves to a strictly farther vertex, so the climb ends within numVertices steps.
  for (bool moved = true; moved;) {
    moved = false;
    const auto from = static_cast<std::size_t>(best);
    const int end = graph.offset[from + 1];
    for (int k = graph.offset[from]; k < end; ++k) {
      const int w = graph.neighbours[static_cast<std::size_t>(k)];
      const double value = vertices[static_cast<std::size_t>(w)].dot(direction);
      if (value > best_value) {
        best_value = value;
        best = w;
        moved = true;
      }
    }
  }
  return best;
}

DistanceBounds triangleConvexMeshDistanceBounds(const Vector3d& t0, const Vector3d& t1, const Vector3d& t2,
                                                const VertexGraph& graph, std::span<const Vector3d> vertices,
                                                double stop_above_m, double tolerance_m, int& warm_vertex) noexcept {
  DistanceBounds out;
  const Vector3d tri[3] = {t0, t1, t2};
  // v: the point of the simplex (points of the Minkowski difference {t - c}) closest to the
  // origin; it starts as one point of the difference.
  Simplex s;
  Vector3d v = t0 - vertices[static_cast<std::size_t>(warm_vertex)];
  s.w[0] = v;
  s.n = 1;
  double v_sq = v.squaredNorm();
  double lower = 0.0;
  for (int it = 0; it < kMaxIterations; ++it) {
    if (v_sq == 0.0) break;  // touching: distance 0
    // Support of the difference against v: the triangle vertex smallest along v minus the
    // body's vertex largest along v; every point m of the difference has v . m >= v . w.
    int k = 0;
    double k_value = tri[0].dot(v);
    for (int i = 1; i < 3; ++i) {
      const double value = tri[i].dot(v);
      if (value < k_value) {
        k_value = value;
        k = i;
      }
    }
    warm_vertex = convexSupportVertex(graph, vertices, v, warm_vertex);
    const Vector3d w = tri[k] - vertices[static_cast<std::size_t>(warm_vertex)];
    ++out.iterations;
    const double v_dot_w = v.dot(w);
    const double norm_v = std::sqrt(v_sq);
    if (v_dot_w / norm_v > lower) {
      lower = v_dot_w / norm_v;
      out.axis = v / norm_v;
    }
    if (lower > stop_above_m || norm_v - lower <= tolerance_m) break;
    // No progress possible: w is no nearer along v than v itself (within rounding).
    if (v_sq - v_dot_w <= 1e-14 * v_sq) break;
    bool repeated = false;
    for (int i = 0; i < s.n; ++i) repeated = repeated || s.w[i] == w;
    if (repeated) break;
    s.w[s.n++] = w;
    Vector3d next;
    if (!closestOnSimplex(s, next)) {  // the origin is inside: the bodies intersect
      v_sq = 0.0;
      break;
    }
    const double next_sq = next.squaredNorm();
    if (next_sq >= v_sq) break;  // rounding: no descent; keep the last bounds
    v = next;
    v_sq = next_sq;
  }
  out.upper_m = std::sqrt(v_sq);
  out.lower_m = std::min(lower, out.upper_m);
  if (!(out.lower_m > 0.0)) {
    out.lower_m = 0.0;
    out.axis = Vector3d::Zero();
  }
  return out;
}

}  // namespace fullarm::haptics
