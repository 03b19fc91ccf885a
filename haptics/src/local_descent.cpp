#include "fullarm/haptics/local_descent.hpp"

#include <utility>

namespace fullarm::haptics {

using Eigen::Isometry3d;
using Eigen::Vector3d;

namespace {

Feature toFeature(const TriMesh& mesh, int tri, const LocalFeature& f) noexcept {
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

}  // namespace

int updateMinimaLocalDescent(const CollisionWorld& world, const arm::ArmData& fk, std::span<LocalMinimum> minima,
                             const LocalDescentParams& params, LocalDescentStats* stats) noexcept {
  LocalDescentStats st;
  int kept = 0;
  for (std::size_t i = 0; i < minima.size(); ++i) {
    LocalMinimum m = minima[i];
    const TriMesh& lmesh = world.linkMesh(m.link);
    const CollisionObject& obj = world.object(m.object);
    const TriMesh& omesh = obj.mesh;
    const Isometry3d X_OL = obj.X_WO.inverse() * fk.X_WL[static_cast<std::size_t>(m.link)];
    int tl = m.tri_link;
    int to = m.tri_object;
    TriangleTriangleResult r = closestPointsInObjectFrame(lmesh, tl, omesh, to, X_OL);
    int it = 0;
    for (; it < params.max_iterations; ++it) {
      // Steepest move among the triangles around the closest feature on either side.
      int best_l = -1;
      int best_o = -1;
      TriangleTriangleResult best = r;
      const double threshold = r.distance_m - params.min_decrease_m;
      for (int t : lmesh.featureTriangles(toFeature(lmesh, tl, r.feature_a))) {
        if (t == tl) continue;
        const TriangleTriangleResult c = closestPointsInObjectFrame(lmesh, t, omesh, to, X_OL);
        if (c.distance_m < threshold && c.distance_m < best.distance_m) {
          best = c;
          best_l = t;
          best_o = to;
        }
      }
      for (int t : omesh.featureTriangles(toFeature(omesh, to, r.feature_b))) {
        if (t == to) continue;
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
    m.feature_link = toFeature(lmesh, tl, r.feature_a);
    m.feature_object = toFeature(omesh, to, r.feature_b);
    m.p_L = X_OL.inverse() * r.p;
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
