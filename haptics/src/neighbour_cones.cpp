#include "fullarm/haptics/neighbour_cones.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

namespace fullarm::haptics {

using Eigen::Vector3d;

namespace {

// Cones narrower than this are not stored (they would almost never hold, and the rounding
// margin of the dot product in conesRejectAllNeighbours needs sin(alpha) well above 1e-16).
constexpr double kMinHalfAngle_rad = 1e-4;
// Absolute part of the angular margin [rad]: covers the rounding of dir . axis and of cos.
constexpr double kAbsoluteMargin_rad = 1e-9;
// Relative part: the per-triangle test's rounding is a few ulps of the coordinates that enter
// it (|w| + |x|), against a true value |g| sin(angle); 1e-12 is ~5000 ulps.
constexpr double kRelativeMargin = 1e-12;

constexpr float kNoCone = 2.0F;

// One constraint of a feature: no neighbour direction g may have dir . g > 0. `scale` is the
// magnitude of the coordinates in the per-triangle test of g.
struct Constraint {
  Vector3d g;
  double scale;
};

// Largest half-angle around unit `axis` whose every direction keeps dir . g <= 0 (with the
// rounding margin) for all constraints; negative when there is none.
double halfAngle(const Vector3d& axis, std::span<const Constraint> constraints) noexcept {
  double alpha = std::numeric_limits<double>::infinity();
  for (const Constraint& c : constraints) {
    const double g_norm = c.g.norm();
    if (!(g_norm > 0.0)) return -1.0;
    // beta = angle(axis, g); the cone's widest dot with g is cos(beta - alpha) <= -sin(margin)
    // exactly when alpha <= beta - pi/2 - margin.
    const double beta = std::atan2(axis.cross(c.g).norm(), axis.dot(c.g));
    const double margin = kRelativeMargin * c.scale / g_norm + kAbsoluteMargin_rad;
    alpha = std::min(alpha, beta - 0.5 * M_PI - margin);
  }
  return alpha;
}

// The stored cone of one feature: the better of the two candidate axes, in float, with the
// threshold rounded towards the smaller cone.
Eigen::Vector4f cone(const Vector3d& pseudo_normal, std::span<const Constraint> constraints) noexcept {
  if (constraints.empty()) return {0.0F, 0.0F, 0.0F, kNoCone};
  Vector3d mean = Vector3d::Zero();
  for (const Constraint& c : constraints) {
    const double n = c.g.norm();
    if (n > 0.0) mean -= c.g / n;
  }
  double best_alpha = -1.0;
  Eigen::Vector3f best_axis = Eigen::Vector3f::Zero();
  Vector3d best_axis_d = Vector3d::Zero();
  for (const Vector3d& candidate : {pseudo_normal, mean}) {
    const double n = candidate.norm();
    if (!(n > 1e-12) || !candidate.allFinite()) continue;
    // The float-rounded axis is the one the test uses: measure the cone around it.
    const Eigen::Vector3f axis_f = (candidate / n).cast<float>();
    const Vector3d axis_d = axis_f.cast<double>();
    const double alpha = halfAngle(axis_d / axis_d.norm(), constraints);
    if (alpha > best_alpha) {
      best_alpha = alpha;
      best_axis = axis_f;
      best_axis_d = axis_d;
    }
  }
  if (!(best_alpha >= kMinHalfAngle_rad)) return {0.0F, 0.0F, 0.0F, kNoCone};
  // dir . axis_d >= |axis_d| cos(alpha - margin) <=> angle(dir, axis) <= alpha - margin.
  const double threshold = best_axis_d.norm() * std::cos(best_alpha - kAbsoluteMargin_rad);
  float t = static_cast<float>(threshold);
  if (static_cast<double>(t) < threshold) t = std::nextafter(t, std::numeric_limits<float>::infinity());
  return {best_axis.x(), best_axis.y(), best_axis.z(), t};
}

}  // namespace

NeighbourCones computeNeighbourCones(const TriMesh& mesh) {
  NeighbourCones out;
  out.vertex.resize(static_cast<std::size_t>(mesh.numVertices()));
  out.edge.resize(static_cast<std::size_t>(mesh.numEdges()));
  std::vector<Constraint> constraints;
  // Vertex v: the one-ring edges w - v (each appears in two triangles of a closed one-ring;
  // duplicates do not change the cone). Test in local descent: dir . w > dir . v.
  for (int v = 0; v < mesh.numVertices(); ++v) {
    constraints.clear();
    const Vector3d& x = mesh.vertex(v);
    for (const int t : mesh.vertexTriangles(v)) {
      const Eigen::Vector3i& tri = mesh.triangle(t);
      for (int k = 0; k < 3; ++k) {
        if (tri[k] == v) continue;
        const Vector3d& w = mesh.vertex(tri[k]);
        constraints.push_back({w - x, w.norm() + x.norm()});
      }
    }
    out.vertex[static_cast<std::size_t>(v)] = cone(mesh.featureNormal({FeatureKind::kVertex, v}), constraints);
  }
  // Edge (a, b), a = the smaller vertex id: for each triangle with third vertex w the inward
  // direction aw - (aw . ab / |ab|^2) ab. Test in local descent:
  // |ab|^2 dir . aw - (aw . ab)(dir . ab) > 0, whose terms are of size |ab|^2 (|w| + |a|).
  for (int e = 0; e < mesh.numEdges(); ++e) {
    constraints.clear();
    const auto ev = mesh.edgeVertices(e);
    const Vector3d& a = mesh.vertex(ev[0]);
    const Vector3d ab = mesh.vertex(ev[1]) - a;
    const double ab_sq = ab.squaredNorm();
    for (const int t : mesh.edgeTriangles(e)) {
      const Eigen::Vector3i& tri = mesh.triangle(t);
      int w = tri[0];
      for (int k = 0; k < 3; ++k) {
        if (tri[k] != ev[0] && tri[k] != ev[1]) w = tri[k];
      }
      const Vector3d aw = mesh.vertex(w) - a;
      constraints.push_back({aw - (aw.dot(ab) / ab_sq) * ab, mesh.vertex(w).norm() + a.norm() + aw.norm()});
    }
    out.edge[static_cast<std::size_t>(e)] = cone(mesh.featureNormal({FeatureKind::kEdge, e}), constraints);
  }
  return out;
}

}  // namespace fullarm::haptics
