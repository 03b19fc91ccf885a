#include "fullarm/haptics/local_descent.hpp"

#include <array>
#include <utility>

namespace fullarm::haptics {

using Eigen::Isometry3d;
using Eigen::Vector3d;

namespace {

// Local index (0..2) of a global feature within triangle `tri`, or -1 (face or not on it).
int localIndex(const TriMesh& mesh, int tri, const Feature& f) noexcept {
  for (int k = 0; k < 3; ++k) {
    if (f.kind == FeatureKind::kVertex && mesh.triangle(tri)[k] == f.index) return k;
    if (f.kind == FeatureKind::kEdge && mesh.triangleEdge(tri, k) == f.index) return k;
  }
  return -1;
}

// Closest points of the tracked triangle pair, warm-started from the previous features: the
// candidate of the previous feature pair is computed alone and kept if it passes the exact
// optimality test of a convex pair (p is the closest point of A to q and q the closest point
// of B to p); otherwise the full triangle-triangle computation runs. Same result, about a
// third of the work when the features did not change.
TriangleTriangleResult warmClosestPoints(const TriMesh& lmesh, int tl, const TriMesh& omesh, int to,
                                         const Isometry3d& X_OL, const LocalMinimum& prev) noexcept {
  const Eigen::Vector3i& ta = lmesh.triangle(tl);
  const Eigen::Vector3i& tb = omesh.triangle(to);
  const std::array<Vector3d, 3> A{X_OL * lmesh.vertex(ta[0]), X_OL * lmesh.vertex(ta[1]), X_OL * lmesh.vertex(ta[2])};
  const std::array<Vector3d, 3> B{omesh.vertex(tb[0]), omesh.vertex(tb[1]), omesh.vertex(tb[2])};
  const int ka = localIndex(lmesh, tl, prev.feature_link);
  const int kb = localIndex(omesh, to, prev.feature_object);
  TriangleTriangleResult r;
  bool have = false;
  if (prev.feature_link.kind == FeatureKind::kVertex && ka >= 0) {
    const PointTriangleResult c = closestPointTriangle(A[static_cast<std::size_t>(ka)], B[0], B[1], B[2]);
    r.p = A[static_cast<std::size_t>(ka)];
    r.q = c.point;
    r.feature_a = {LocalFeature::Kind::kVertex, static_cast<std::uint8_t>(ka)};
    r.feature_b = c.feature;
    have = true;
  } else if (prev.feature_object.kind == FeatureKind::kVertex && kb >= 0) {
    const PointTriangleResult c = closestPointTriangle(B[static_cast<std::size_t>(kb)], A[0], A[1], A[2]);
    r.p = c.point;
    r.q = B[static_cast<std::size_t>(kb)];
    r.feature_a = c.feature;
    r.feature_b = {LocalFeature::Kind::kVertex, static_cast<std::uint8_t>(kb)};
    have = true;
  } else if (prev.feature_link.kind == FeatureKind::kEdge && prev.feature_object.kind == FeatureKind::kEdge &&
             ka >= 0 && kb >= 0) {
    const auto ia = static_cast<std::size_t>(ka);
    const auto ib = static_cast<std::size_t>(kb);
    const SegmentSegmentResult c = closestPointsSegmentSegment(A[ia], A[(ia + 1) % 3], B[ib], B[(ib + 1) % 3]);
    if (c.s > 0.0 && c.s < 1.0 && c.t > 0.0 && c.t < 1.0) {
      r.p = c.p;
      r.q = c.q;
      r.feature_a = {LocalFeature::Kind::kEdge, static_cast<std::uint8_t>(ka)};
      r.feature_b = {LocalFeature::Kind::kEdge, static_cast<std::uint8_t>(kb)};
      have = true;
    }
  }
  if (have) {
    r.distance_m = (r.q - r.p).norm();
    const double accept = r.distance_m - 1e-15 * (1.0 + r.distance_m);
    if (r.distance_m > 0.0 && accept > 0.0 && squaredDistancePointTriangle(r.q, A[0], A[1], A[2]) >= accept * accept &&
        squaredDistancePointTriangle(r.p, B[0], B[1], B[2]) >= accept * accept) {
      return r;
    }
  }
  return closestPointsTriangleTriangle(A[0], A[1], A[2], B[0], B[1], B[2]);
}

// First-order screening of a neighbour triangle t of feature f (a vertex or an edge holding
// the closest point x): can a point of t be closer to the target (in direction `dir` from x)
// than x? The distance over a flat triangle is convex, so this holds exactly when some
// direction into t from x has a positive component along dir: for a vertex, one of t's two
// edges leaving it; for an edge, t's in-plane direction perpendicular to it.
bool neighbourMayBeCloser(const TriMesh& mesh, const Feature& f, int t, const Vector3d& dir) noexcept {
  const Eigen::Vector3i& tri = mesh.triangle(t);
  if (f.kind == FeatureKind::kVertex) {
    const Vector3d& v = mesh.vertex(f.index);
    for (int k = 0; k < 3; ++k) {
      if (tri[k] != f.index && dir.dot(mesh.vertex(tri[k]) - v) > 0.0) return true;
    }
    return false;
  }
  const auto ev = mesh.edgeVertices(f.index);
  const Vector3d& a = mesh.vertex(ev[0]);
  const Vector3d ab = mesh.vertex(ev[1]) - a;
  int w = tri[0];
  for (int k = 0; k < 3; ++k) {
    if (tri[k] != ev[0] && tri[k] != ev[1]) w = tri[k];
  }
  const Vector3d aw = mesh.vertex(w) - a;
  // Component of a->w perpendicular to the edge, scaled by |ab|^2 (no division).
  const Vector3d inward = ab.squaredNorm() * aw - aw.dot(ab) * ab;
  return dir.dot(inward) > 0.0;
}

}  // namespace

int updateMinimaLocalDescent(const CollisionWorld& world, const arm::ArmData& fk, std::span<LocalMinimum> minima,
                             const LocalDescentParams& params, LocalDescentStats* stats) noexcept {
  LocalDescentStats st;
  int kept = 0;
  int pose_link = -1;
  int pose_object = -1;
  Isometry3d X_OL = Isometry3d::Identity();
  Isometry3d X_LO = Isometry3d::Identity();
  for (std::size_t i = 0; i < minima.size(); ++i) {
    LocalMinimum m = minima[i];
    const TriMesh& lmesh = world.linkMesh(m.link);
    const CollisionObject& obj = world.object(m.object);
    const TriMesh& omesh = obj.mesh;
    // Minima come grouped by link/object pair: the relative pose is computed once per pair.
    if (m.link != pose_link || m.object != pose_object) {
      X_OL = obj.X_WO.inverse() * fk.X_WL[static_cast<std::size_t>(m.link)];
      X_LO = X_OL.inverse();
      pose_link = m.link;
      pose_object = m.object;
    }
    int tl = m.tri_link;
    int to = m.tri_object;
    TriangleTriangleResult r = warmClosestPoints(lmesh, tl, omesh, to, X_OL, m);
    int it = 0;
    for (; it < params.max_iterations; ++it) {
      // Steepest move among the triangles around the closest feature on either side.
      int best_l = -1;
      int best_o = -1;
      TriangleTriangleResult best = r;
      const double threshold = r.distance_m - params.min_decrease_m;
      if (threshold <= 0.0) break;  // touching: nothing can be closer
      // Screening: a neighbour can only lower the distance if it comes closer to the other
      // side's closest point than d (the pair distance is convex, so (p, q) is otherwise
      // already optimal for that neighbour); only then is the triangle pair evaluated.
      const Vector3d u_O = (r.q - r.p) / r.distance_m;
      const Vector3d u_L = X_LO.linear() * u_O;
      const Feature cur_l = meshFeature(lmesh, tl, r.feature_a);
      const Feature cur_o = meshFeature(omesh, to, r.feature_b);
      for (int t : lmesh.featureTriangles(cur_l)) {
        if (t == tl || !neighbourMayBeCloser(lmesh, cur_l, t, u_L)) continue;
        const TriangleTriangleResult c = closestPointsInObjectFrame(lmesh, t, omesh, to, X_OL);
        if (c.distance_m < threshold && c.distance_m < best.distance_m) {
          best = c;
          best_l = t;
          best_o = to;
        }
      }
      for (int t : omesh.featureTriangles(cur_o)) {
        if (t == to || !neighbourMayBeCloser(omesh, cur_o, t, -u_O)) continue;
        const TriangleTriangleResult c = closestPointsInObjectFrame(lmesh, tl, omesh, t, X_OL);
        if (c.distance_m < threshold && c.distance_m < best.distance_m) {
          best = c;
          best_l = tl;
          best_o = t;
        }
      }
      if (best_l < 0) break;
      tl = best_l;
      to = best_o;
      r = best;
      ++st.steps;
    }
    if (it == params.max_iterations) ++st.minima_at_iteration_cap;

    m.previous_distance_m = m.distance_m;
    m.tri_link = tl;
    m.tri_object = to;
    m.feature_link = meshFeature(lmesh, tl, r.feature_a);
    m.feature_object = meshFeature(omesh, to, r.feature_b);
    m.p_L = X_LO * r.p;
    m.p_O = r.q;
    m.distance_m = r.distance_m;
    if (r.distance_m > 0.0) {
      m.u_W = obj.X_WO.linear() * ((r.q - r.p) / r.distance_m);
    } else {
      const Vector3d& n = omesh.featureNormal(m.feature_object);
      m.u_W = -(obj.X_WO.linear() * (n.squaredNorm() > 0.0 ? n : omesh.faceNormal(to)));
    }
    if (m.distance_m > params.drop_beyond_m) {
      ++st.dropped;
      continue;
    }
    // Merge with an earlier survivor that reached the same feature pair.
    bool duplicate = false;
    for (int k = 0; k < kept; ++k) {
      if (sameFeaturePair(minima[static_cast<std::size_t>(k)], m)) {
        duplicate = true;
        break;
      }
    }
    if (duplicate) {
      ++st.merged;
      continue;
    }
    minima[static_cast<std::size_t>(kept++)] = m;
  }
  if (stats != nullptr) *stats = st;
  return kept;
}

}  // namespace fullarm::haptics
