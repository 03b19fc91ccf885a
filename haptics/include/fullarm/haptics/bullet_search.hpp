#pragma once
/// @file
/// Bullet (double precision) beside SNCH: an alternative global search with the same output
/// and pruning, selectable at run time through GlobalSearch, and GJK/EPA penetration depths of
/// a link into an object (the hand-only study statistics).
///
/// Each object is a btBvhTriangleMeshShape (margin 0). For a capsule link, Bullet's BVH picks the
/// object triangles whose boxes overlap the capsule's box grown by the cutoff
/// (capsuleCandidateTriangles), and each goes through SNCH's exact capsule test
/// (evaluateCapsuleTriangle): Bullet's own capsule-triangle GJK is not used to discard
/// triangles, because it can overestimate a distance by centimetres when the capsule lies
/// parallel to a face (seen on a box face: 54.5 mm for 22.7 mm). For a mesh link, the search
/// asks Bullet for the closest points of every link triangle and object triangle within the
/// cutoff: btCollisionWorld::contactPairTest between the link (a btCompoundShape of zero-margin
/// btTriangleShape children, one per link triangle) and the object with
/// ContactResultCallback::m_closestDistanceThreshold = L; Bullet's bounding-volume trees pick the
/// triangle pairs whose boxes come within L and run GJK (EPA when they intersect) on each, and
/// every reported pair goes through SNCH's exact leaf test (evaluateTrianglePair). Then the same
/// merge of feature pairs and the same endpoint-radius pruning, so both searches return the same
/// minima.

#include <Eigen/Geometry>
#include <memory>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/minima.hpp"

namespace fullarm::haptics {

/// Closest points of one link triangle (or a capsule link) and one object triangle as Bullet
/// reports them.
struct TrianglePairPoints {
  int tri_link = -1;  ///< -1 for a capsule link
  int tri_object = -1;
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  ///< on the link triangle, world [m]
  Eigen::Vector3d q_W = Eigen::Vector3d::Zero();  ///< on the object triangle, world [m]
  double distance_m = 0.0;                        ///< negative when the triangles intersect (EPA depth)
};

/// Penetration of a link into an object by GJK/EPA.
struct LinkPenetration {
  bool penetrating = false;
  double depth_m = 0.0;                           ///< >= 0; 0 when apart
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();  ///< deepest point of the link, world [m]
  Eigen::Vector3d q_W = Eigen::Vector3d::Zero();  ///< its counterpart on the object surface, world [m]
  bool solid_object = false;                      ///< depth measured into a convex solid (see penetration())
};

/// The Bullet alternative global search. Built for one CollisionWorld (its meshes are copied
/// into Bullet's structures); search() must be given that world (same meshes; object poses may
/// change between calls).
class BulletGlobalSearch final : public GlobalSearch {
 public:
  /// @throws std::invalid_argument if the world has no link with geometry
  explicit BulletGlobalSearch(const CollisionWorld& world);
  ~BulletGlobalSearch() override;

  /// Every local minimum within cutoff_m, merged by feature pair and pruned (as SNCH).
  /// @throws std::invalid_argument if `world` does not have the link/object meshes this search
  ///   was built for
  void search(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
              std::vector<LocalMinimum>& out) override;
  [[nodiscard]] std::string_view name() const noexcept override { return "bullet"; }

  /// Bullet's per-triangle closest points (GJK, contactPairTest) between `link` at X_WL and
  /// `object` at X_WO, for every triangle pair within cutoff_m as Bullet measures it (one entry
  /// per pair, sorted by (tri_link, tri_object); tri_link -1 for a capsule link). Appends to
  /// `out`.
  void closestTrianglePairs(int link, const Eigen::Isometry3d& X_WL, int object, const Eigen::Isometry3d& X_WO,
                            double cutoff_m, std::vector<TrianglePairPoints>& out);

  /// The triangles of `object` (at X_WO) that Bullet's BVH reports against the box of capsule
  /// link `link` (at X_WL) grown by its radius and cutoff_m, in the object frame: every triangle
  /// within cutoff_m of the capsule is among them. Appends to `out`, sorted, each once.
  /// @throws std::invalid_argument if `link` is not a capsule link
  void capsuleCandidateTriangles(int link, const Eigen::Isometry3d& X_WL, int object, const Eigen::Isometry3d& X_WO,
                                 double cutoff_m, std::vector<int>& out) const;

  /// GJK/EPA penetration depth of `link` (its capsule, or the convex hull of its mesh) into
  /// `object`. A convex object (every vertex on the inner side of every face plane) is taken as
  /// a solid: the depth is the EPA penetration depth of the two convex shapes, exact however
  /// deep. Any other object is a surface: the depth is the deepest GJK/EPA penetration of the
  /// link into one of its triangles, which equals the solid depth while the link's axis stays
  /// outside the surface (penetration shallower than the link radius) and under-estimates it
  /// beyond.
  [[nodiscard]] LinkPenetration penetration(int link, const Eigen::Isometry3d& X_WL, int object,
                                            const Eigen::Isometry3d& X_WO);

  /// Number of triangle pairs (capsule links: candidate triangles) Bullet reported in the last
  /// search().
  [[nodiscard]] long lastTrianglePairs() const noexcept { return last_pairs_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::vector<TrianglePairPoints> pairs_;
  std::vector<int> triangles_;
  long last_pairs_ = 0;
};

}  // namespace fullarm::haptics
