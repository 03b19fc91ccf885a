#include "fullarm/haptics/local_descent.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <utility>

namespace fullarm::haptics {

using Eigen::Isometry3d;
using Eigen::Vector3d;

namespace {

// Local index (0..2) of a global feature within triangle `tri`, or -1 (face or not on it).
int localIndex(const TriMesh& mesh, int tri, const Feature& f) noexcept {
  if (f.kind == FeatureKind::kVertex) {
    const Eigen::Vector3i& v = mesh.triangle(tri);
    return v[0] == f.index ? 0 : v[1] == f.index ? 1 : v[2] == f.index ? 2 : -1;
  }
  if (f.kind == FeatureKind::kEdge) {
    for (int k = 0; k < 3; ++k) {
      if (mesh.triangleEdge(tri, k) == f.index) return k;
    }
  }
  return -1;
}

// Local numbering (in triangle `tri`) of a mesh feature of the previous tick: the warm-start
// guess of closestPointsTriangleTriangleWarm (the face when the feature is not on `tri`).
LocalFeature localGuess(const TriMesh& mesh, int tri, const Feature& f) noexcept {
  const int k = localIndex(mesh, tri, f);
  if (k < 0) return {};
  return {f.kind == FeatureKind::kVertex ? LocalFeature::Kind::kVertex : LocalFeature::Kind::kEdge,
          static_cast<std::uint8_t>(k)};
}

// A link triangle moved into the object frame, prepared for repeated queries.
PreparedTriangle linkTriangle(const TriMesh& mesh, int t, const Isometry3d& X_OL) noexcept {
  const Eigen::Vector3i& v = mesh.triangle(t);
  return prepareTriangle(X_OL * mesh.vertex(v[0]), X_OL * mesh.vertex(v[1]), X_OL * mesh.vertex(v[2]));
}

PreparedTriangle objectTriangle(const TriMesh& mesh, int t) noexcept {
  const Eigen::Vector3i& v = mesh.triangle(t);
  return prepareTriangle(mesh.vertex(v[0]), mesh.vertex(v[1]), mesh.vertex(v[2]));
}

// meshFeature (snch.hpp), inlined here: called several times per minimum and tick.
inline Feature globalFeature(const TriMesh& mesh, int tri, const LocalFeature& f) noexcept {
  if (f.kind == LocalFeature::Kind::kVertex) return {FeatureKind::kVertex, mesh.triangle(tri)[f.index]};
  if (f.kind == LocalFeature::Kind::kEdge) return {FeatureKind::kEdge, mesh.triangleEdge(tri, f.index)};
  return {FeatureKind::kFace, tri};
}

// Link/object pairs whose runs the merge remembers (see updateMinimaLocalDescent); beyond
// this many runs every survivor is compared.
constexpr int kMaxRuns = 64;

inline std::uint64_t pairKey(int link, int object) noexcept {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(link)) << 32) | static_cast<std::uint32_t>(object);
}

// First-order screening of the neighbour triangles t of feature f (a vertex or an edge
// holding the closest point x): can a point of t be closer to the target (in direction `dir`
// from x) than x? The distance over a flat triangle is convex, so this holds exactly when some
// direction into t from x has a positive component along dir: for a vertex, one of t's two
// edges leaving it; for an edge, t's in-plane direction perpendicular to it. The per-feature
// terms are computed once for all neighbours.
class NeighbourScreen {
 public:
  NeighbourScreen(const TriMesh& mesh, const Feature& f, const Vector3d& dir) noexcept
      : mesh_(mesh), feature_(f), dir_(dir) {
    if (f.kind == FeatureKind::kVertex) {
      dir_a_ = dir.dot(mesh.vertex(f.index));
    } else if (f.kind == FeatureKind::kEdge) {
      const auto ev = mesh.edgeVertices(f.index);
      v0_ = ev[0];
      v1_ = ev[1];
      a_ = mesh.vertex(v0_);
      ab_ = mesh.vertex(v1_) - a_;
      ab_sq_ = ab_.squaredNorm();
      dir_ab_ = dir.dot(ab_);
    }
  }

  [[nodiscard]] bool mayBeCloser(int t) const noexcept {
    const Eigen::Vector3i& tri = mesh_.triangle(t);
    if (feature_.kind == FeatureKind::kVertex) {
      // dir . (w - v) > 0 for one of the two other vertices w.
      const int v = feature_.index;
      const int w0 = tri[0] == v ? tri[1] : tri[0];
      const int w1 = tri[2] == v ? tri[1] : tri[2];
      return dir_.dot(mesh_.vertex(w0)) > dir_a_ || dir_.dot(mesh_.vertex(w1)) > dir_a_;
    }
    int w = tri[0];
    for (int k = 0; k < 3; ++k) {
      if (tri[k] != v0_ && tri[k] != v1_) w = tri[k];
    }
    // dir . inward with inward = |ab|^2 aw - (aw . ab) ab, the component of a->w
    // perpendicular to the edge scaled by |ab|^2 (no division).
    const Vector3d aw = mesh_.vertex(w) - a_;
    return ab_sq_ * dir_.dot(aw) - aw.dot(ab_) * dir_ab_ > 0.0;
  }

 private:
  const TriMesh& mesh_;
  Feature feature_;
  Vector3d dir_;
  double dir_a_ = 0.0;
  int v0_ = -1;
  int v1_ = -1;
  Vector3d a_ = Vector3d::Zero();
  Vector3d ab_ = Vector3d::Zero();
  double ab_sq_ = 0.0;
  double dir_ab_ = 0.0;
};

// Local descent of a minimum of a capsule link: the capsule's side is exact (its point is the
// projection of the object point), so only the object side walks, from feature to feature. The
// segment [a, b] is in the object frame. Each step computes the segment's closest pair with the
// current feature f alone (capsuleFeatureClosest: a vertex or an edge costs a point or a
// segment projection, no triangle query), moves to the feature that holds the object point
// when that is not f (an edge's end, a face's rim), then tests the triangles around f with the
// first-order test toward the segment's point (the distance to the segment is convex, with the
// same gradient as the distance to that point): inside f's rejection cone none can come closer;
// otherwise each one that may is queried (closestPointsSegmentTriangle) and the walk moves to the
// closest if it lowers the distance by more than min_decrease_m. The minimum is then filled
// from its final feature's pair, as the global search fills it (capsuleMinimumFromPair).
void descendCapsuleMinimum(const Vector3d& a, const Vector3d& b, double radius_m, const Isometry3d& X_LO,
                           const CollisionObject& obj, const LocalDescentParams& params, LocalMinimum& m,
                           LocalDescentStats& st) noexcept {
  const TriMesh& omesh = obj.mesh;
  int to = m.tri_object;
  Feature f = m.feature_object;
  CapsuleFeaturePair r = capsuleFeatureClosest(a, b, omesh, f);
  int it = 0;
  for (; it < params.max_iterations; ++it) {
    if (!(r.holder == f)) {
      // The closest point of f lies on a smaller feature of it (same point, same distance).
      f = r.holder;
      r = capsuleFeatureClosest(a, b, omesh, f);
      if (!(r.holder == f)) break;  // rounding at a vertex: keep the pair as it is
    }
    if (!(r.distance_sq > 0.0) || f.kind == FeatureKind::kFace) break;  // touching; a face has no neighbours
    const double d = std::sqrt(r.distance_sq);
    const double threshold = d - params.min_decrease_m;
    if (threshold <= 0.0) break;
    const Vector3d dir = (r.on_segment_m - r.q_m) / d;
    if (params.cone_screening && conesRejectAllNeighbours(obj.cones, f, dir)) {
      ++st.cone_rejected;
      break;
    }
    const NeighbourScreen screen(omesh, f, dir);
    double best_sq = threshold * threshold;
    int best_t = -1;
    Feature best_f;
    Vector3d best_dir = Vector3d::Zero();
    for (int t : omesh.featureTriangles(f)) {
      ++st.screened;
      if (!screen.mayBeCloser(t)) continue;
      // Re-screening at the step's best pair (s', q') so far: s' is the segment's point closest
      // to q', so when t shares q''s feature and the first-order test at q' rejects t, q' is also
      // t's point closest to s' and (s', q') is the closest pair of the segment and t (two convex
      // sets): t cannot beat the best.
      if (params.rescreen_neighbours && best_t >= 0 && best_f.kind != FeatureKind::kFace &&
          localIndex(omesh, t, best_f) >= 0 && !NeighbourScreen(omesh, best_f, best_dir).mayBeCloser(t)) {
        ++st.rescreened;
        continue;
      }
      ++st.evaluated;
      const SegmentTriangleResult c = closestPointsSegmentTriangle(a, b, objectTriangle(omesh, t));
      if (c.distance_sq < best_sq) {
        best_sq = c.distance_sq;
        best_t = t;
        best_f = globalFeature(omesh, t, c.feature_t);
        best_dir = c.distance_sq > 0.0 ? Vector3d((c.p - c.q) / std::sqrt(c.distance_sq)) : Vector3d::Zero();
      }
    }
    if (best_t < 0) break;
    to = best_t;
    f = best_f;
    r = capsuleFeatureClosest(a, b, omesh, f);
    ++st.steps;
  }
  if (it == params.max_iterations) ++st.minima_at_iteration_cap;
  // A vertex or edge feature is held by every triangle around it; keep one that holds it.
  if (f.kind == FeatureKind::kFace) to = f.index;
  if (f.kind != FeatureKind::kFace && localIndex(omesh, to, f) < 0) to = omesh.featureTriangles(f)[0];
  const double previous = m.distance_m;
  capsuleMinimumFromPair(r, radius_m, X_LO, omesh, to, f, m);
  m.previous_distance_m = previous;
  m.u_W = obj.X_WO.linear() * m.u_W;
}

}  // namespace

// §3.2.1: global search within the cutoff, pruning and local descent of the minima (reports/equations.md).
int updateMinimaLocalDescent(const CollisionWorld& world, const arm::ArmData& fk, std::span<LocalMinimum> minima,
                             const LocalDescentParams& params, LocalDescentStats* stats) noexcept {
  LocalDescentStats st;
  int kept = 0;
  int pose_link = -1;
  int pose_object = -1;
  Isometry3d X_OL = Isometry3d::Identity();
  Isometry3d X_LO = Isometry3d::Identity();
  Vector3d seg_a = Vector3d::Zero();  // a capsule link's segment in the object frame
  Vector3d seg_b = Vector3d::Zero();
  // Runs of equal link/object pairs in input order (minima normally come grouped by pair).
  std::array<std::uint64_t, kMaxRuns> runs;
  int num_runs = 0;
  bool runs_overflowed = false;
  int run_begin = 0;         // first survivor of the current run
  bool full_scan = false;    // the current pair had an earlier run: compare every survivor
  int cached_link_tri = -1;  // link triangle held by cached_link (prepared at the current pose)
  PreparedTriangle cached_link{};
  // Prepared triangles of the neighbours evaluated in a step: the best one's slot is kept, so
  // the step moves onto an already prepared triangle.
  std::array<PreparedTriangle, 2> candidates;
  PreparedTriangle moved_link;  // the link triangle after a link-side step
  for (std::size_t i = 0; i < minima.size(); ++i) {
    // Updated in place; a survivor is moved down to minima[kept] at the end (kept <= i).
    LocalMinimum& m = minima[i];
    const CollisionObject& obj = world.object(m.object);
    const bool capsule = world.linkShape(m.link) == LinkShape::kCapsule;
    // Minima come grouped by link/object pair: the relative pose is computed once per pair.
    if (m.link != pose_link || m.object != pose_object) {
      const std::uint64_t key = pairKey(m.link, m.object);
      full_scan = runs_overflowed;
      for (int k = 0; k < num_runs && !full_scan; ++k) full_scan = runs[static_cast<std::size_t>(k)] == key;
      if (num_runs < kMaxRuns) {
        runs[static_cast<std::size_t>(num_runs++)] = key;
      } else {
        runs_overflowed = true;
      }
      run_begin = kept;
      X_OL = obj.X_WO.inverse() * fk.X_WL[static_cast<std::size_t>(m.link)];
      X_LO = X_OL.inverse();
      pose_link = m.link;
      pose_object = m.object;
      cached_link_tri = -1;
      if (capsule) {
        const Capsule& c = world.linkCapsule(m.link);
        seg_a = X_OL * c.a_m;
        seg_b = X_OL * c.b_m;
      }
    }
    if (capsule) {
      descendCapsuleMinimum(seg_a, seg_b, world.linkCapsule(m.link).radius_m, X_LO, obj, params, m, st);
    } else {
      const TriMesh& lmesh = world.linkMesh(m.link);
      const NeighbourCones& lcones = world.linkCones(m.link);
      const TriMesh& omesh = obj.mesh;
      int tl = m.tri_link;
      int to = m.tri_object;
      // The tracked pair at the new pose. Most pairs keep their features between ticks: their
      // optimality certificate (the KKT conditions, certifyEdgeEdgePair / certifyVertexTriangle)
      // is checked on the raw vertices first, and the triangles are prepared only when it fails
      // or when a neighbour is evaluated against them. Otherwise the warm-started query runs.
      // Minima of one link/object pair often start on the same link triangle (a capsule's long
      // strips hold several): its prepared copy in the object frame is reused while the pose is.
      const PreparedTriangle* A = nullptr;  // the link triangle, prepared on first use
      auto prepareLink = [&]() noexcept {
        if (tl != cached_link_tri) {
          cached_link = linkTriangle(lmesh, tl, X_OL);
          cached_link_tri = tl;
        }
        return &cached_link;
      };
      PreparedTriangle B;  // the object triangle, prepared on first use (b_ready)
      bool b_ready = false;
      const LocalFeature guess_l = localGuess(lmesh, tl, m.feature_link);
      const LocalFeature guess_o = localGuess(omesh, to, m.feature_object);
      TriangleTriangleResult r;
      bool certified = false;
      double d_sq = 0.0;
      if (guess_l.kind == LocalFeature::Kind::kEdge && guess_o.kind == LocalFeature::Kind::kEdge) {
        const Eigen::Vector3i& lt = lmesh.triangle(tl);
        const Eigen::Vector3i& ot = omesh.triangle(to);
        const Vector3d& l0 = lmesh.vertex(lt[guess_l.index]);
        const Vector3d& l1 = lmesh.vertex(lt[(guess_l.index + 1) % 3]);
        const Vector3d& o0 = omesh.vertex(ot[guess_o.index]);
        const Vector3d& o1 = omesh.vertex(ot[(guess_o.index + 1) % 3]);
        certified = certifyEdgeEdgePair(X_OL * l0, X_OL * l1, X_OL.linear() * lmesh.faceNormal(tl).cross(l1 - l0), o0,
                                        o1, omesh.faceNormal(to).cross(o1 - o0), r.p, r.q, d_sq);
      } else if (guess_o.kind == LocalFeature::Kind::kVertex && guess_l.kind != LocalFeature::Kind::kVertex) {
        const Eigen::Vector3i& ot = omesh.triangle(to);
        const Vector3d& v = omesh.vertex(ot[guess_o.index]);
        A = prepareLink();
        certified = certifyVertexTriangle(v, omesh.vertex(ot[(guess_o.index + 1) % 3]) - v,
                                          omesh.vertex(ot[(guess_o.index + 2) % 3]) - v, *A, r.p, d_sq, r.feature_a);
        r.q = v;
      }
      if (certified) {
        r.distance_m = std::sqrt(d_sq);
        if (guess_o.kind == LocalFeature::Kind::kEdge) r.feature_a = guess_l;
        r.feature_b = guess_o;
      } else {
        if (A == nullptr) A = prepareLink();
        B = objectTriangle(omesh, to);
        b_ready = true;
        r = closestPointsTriangleTriangleWarm(*A, B, guess_l, guess_o);
      }
      // A certified pair keeps the tracked features.
      Feature cur_l = certified && guess_o.kind == LocalFeature::Kind::kEdge ? m.feature_link
                                                                             : globalFeature(lmesh, tl, r.feature_a);
      Feature cur_o = certified ? m.feature_object : globalFeature(omesh, to, r.feature_b);
      int it = 0;
      for (; it < params.max_iterations; ++it) {
        // Steepest move among the triangles around the closest feature on either side.
        const double threshold = r.distance_m - params.min_decrease_m;
        if (threshold <= 0.0) break;  // touching: nothing can be closer
        // Screening: a neighbour can only lower the distance if it comes closer to the other
        // side's closest point than d (the pair distance is convex, so (p, q) is otherwise
        // already optimal for that neighbour); only then is the triangle pair evaluated.
        const Vector3d u_O = (r.q - r.p) / r.distance_m;
        const Vector3d u_L = X_LO.linear() * u_O;
        TriangleTriangleResult best = r;
        int best_t = -1;
        bool best_link_side = false;
        bool best_prepared = false;  // the best neighbour's prepared triangle is in candidates[best_slot]
        int best_slot = 0;
        int free_slot = 0;
        // A face feature has no neighbours to screen; a direction inside the feature's
        // rejection cone rejects them all at once (exact, see neighbour_cones.hpp).
        const bool link_cone = params.cone_screening && conesRejectAllNeighbours(lcones, cur_l, u_L);
        const bool object_cone = params.cone_screening && conesRejectAllNeighbours(obj.cones, cur_o, -u_O);
        st.cone_rejected += static_cast<int>(link_cone) + static_cast<int>(object_cone);
        if (cur_l.kind != FeatureKind::kFace && !link_cone) {
          const NeighbourScreen screen(lmesh, cur_l, u_L);
          for (int t : lmesh.featureTriangles(cur_l)) {
            if (t == tl) continue;
            ++st.screened;
            if (!screen.mayBeCloser(t)) continue;
            // Warm-started: B and its closest feature are unchanged, t's is unknown (face).
            ++st.evaluated;
            if (!b_ready) {
              B = objectTriangle(omesh, to);
              b_ready = true;
            }
            PreparedTriangle& cand = candidates[static_cast<std::size_t>(free_slot)];
            cand = linkTriangle(lmesh, t, X_OL);
            const TriangleTriangleResult c = closestPointsTriangleTriangleWarm(cand, B, LocalFeature{}, r.feature_b);
            if (c.distance_m < threshold && c.distance_m < best.distance_m) {
              best = c;
              best_t = t;
              best_link_side = true;
              best_prepared = true;
              best_slot = free_slot;
              free_slot ^= 1;
            }
          }
        }
        if (cur_o.kind != FeatureKind::kFace && !object_cone) {
          const NeighbourScreen screen(omesh, cur_o, -u_O);
          for (int t : omesh.featureTriangles(cur_o)) {
            if (t == to) continue;
            ++st.screened;
            if (!screen.mayBeCloser(t)) continue;
            // Re-screening: once a neighbour t1 of this step has lowered the distance with the
            // link triangle A unchanged, its pair (p', q') is optimal over A x t1, so p' is A's
            // closest point to q'. If q' lies on a feature that t shares with t1 and the first-
            // order test shows that no point of t is closer to p' than q', then (p', q') is also
            // optimal over A x t: t cannot lower the distance below the best, and its (costly)
            // evaluation is skipped. Exact: same screening test as above, at the new pair.
            if (params.rescreen_neighbours && best_t >= 0 && !best_link_side && best.distance_m > 0.0) {
              const Feature shared = globalFeature(omesh, best_t, best.feature_b);
              if (shared.kind != FeatureKind::kFace && localIndex(omesh, t, shared) >= 0 &&
                  !NeighbourScreen(omesh, shared, (best.p - best.q) / best.distance_m).mayBeCloser(t)) {
                ++st.rescreened;
                continue;
              }
            }
            ++st.evaluated;
            if (A == nullptr) A = prepareLink();
            // The link edge against t through the spanning kernel on t's raw vertices (the
            // dominant case; bit for bit the warm start below); t is prepared only when the
            // kernel does not decide, or later if the step moves onto it and it is needed.
            TriangleTriangleResult c;
            bool prepared = false;
            const Eigen::Vector3i& tv = omesh.triangle(t);
            if (r.feature_a.kind != LocalFeature::Kind::kEdge ||
                !closestPointsEdgeTriangleSpanning(*A, r.feature_a.index, omesh.vertex(tv[0]), omesh.vertex(tv[1]),
                                                   omesh.vertex(tv[2]), c)) {
              PreparedTriangle& cand = candidates[static_cast<std::size_t>(free_slot)];
              cand = objectTriangle(omesh, t);
              c = closestPointsTriangleTriangleWarm(*A, cand, r.feature_a, LocalFeature{});
              prepared = true;
            }
            if (c.distance_m < threshold && c.distance_m < best.distance_m) {
              best = c;
              best_t = t;
              best_link_side = false;
              best_prepared = prepared;
              best_slot = free_slot;
              if (prepared) free_slot ^= 1;
            }
          }
        }
        if (best_t < 0) break;
        if (best_link_side) {
          tl = best_t;
          moved_link = candidates[static_cast<std::size_t>(best_slot)];
          A = &moved_link;
        } else {
          to = best_t;
          b_ready = best_prepared;
          if (best_prepared) B = candidates[static_cast<std::size_t>(best_slot)];
        }
        r = best;
        cur_l = globalFeature(lmesh, tl, r.feature_a);
        cur_o = globalFeature(omesh, to, r.feature_b);
        ++st.steps;
      }
      if (it == params.max_iterations) ++st.minima_at_iteration_cap;

      m.previous_distance_m = m.distance_m;
      m.tri_link = tl;
      m.tri_object = to;
      m.feature_link = cur_l;
      m.feature_object = cur_o;
      m.p_L = X_LO * r.p;
      m.p_O = r.q;
      m.distance_m = r.distance_m;
      if (r.distance_m > 0.0) {
        m.u_W = obj.X_WO.linear() * ((r.q - r.p) / r.distance_m);
      } else {
        const Vector3d& n = omesh.featureNormal(m.feature_object);
        m.u_W = -(obj.X_WO.linear() * (n.squaredNorm() > 0.0 ? n : omesh.faceNormal(to)));
      }
    }
    if (m.distance_m > params.drop_beyond_m) {
      ++st.dropped;
      continue;
    }
    // Merge with an earlier survivor that reached the same feature pair. Only survivors of
    // the same link/object pair can match: those of the current run of that pair, unless the
    // pair already had an earlier run (input not grouped) or the run table overflowed.
    // The object feature's index differs for almost every other survivor: compared first.
    bool duplicate = false;
    const int object_feature = m.feature_object.index;
    for (int k = full_scan ? 0 : run_begin; k < kept && !duplicate; ++k) {
      const LocalMinimum& other = minima[static_cast<std::size_t>(k)];
      duplicate = other.feature_object.index == object_feature && sameFeaturePair(other, m);
    }
    if (duplicate) {
      ++st.merged;
      continue;
    }
    if (static_cast<std::size_t>(kept) != i) minima[static_cast<std::size_t>(kept)] = m;
    ++kept;
  }
  if (stats != nullptr) *stats = st;
  return kept;
}

}  // namespace fullarm::haptics
