#pragma once
/// @file
/// CollisionWorld: the arm's link meshes and the environment objects, each with its SNCH, and
/// the scene-level global search (every link with a mesh x every object, then pruning).

#include <Eigen/Geometry>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/minima.hpp"
#include "fullarm/haptics/neighbour_cones.hpp"
#include "fullarm/haptics/snch.hpp"
#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// One environment object: a mesh in its own frame O and its pose in the world.
struct CollisionObject {
  std::string name;
  TriMesh mesh;
  SnchTree tree;
  Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
  NeighbourCones cones;  ///< local descent's neighbour-rejection cones of `mesh`
};

/// How an arm link takes part in the queries.
enum class LinkShape {
  kNone,     ///< no collision geometry: never queried
  kCapsule,  ///< the exact capsule of its LinkGeometry (segment and radius): linkCapsule()
  kMesh,     ///< a triangle mesh given with setLinkMesh (for example an imported hand): linkMesh()
};

/// The arm's link geometry and the environment objects with their hierarchies. A link whose
/// LinkGeometry is a capsule is queried as that exact capsule (its segment and radius, link
/// frame): distances equal the true capsule distance. setLinkMesh gives a link a triangle mesh
/// instead, expressed in the link frame (so X_WL from forward kinematics places it); object
/// meshes are in their object frame. Not thread-safe for mutation; const queries may run
/// concurrently with separate scratch.
///
/// Lifetime: a CollisionWorld refers to the arm model it was built for (model()) and keeps no
/// copy of it; that model must outlive the world and every copy of it.
class CollisionWorld {
 public:
  struct Options {};

  /// Takes every link whose geometry is a capsule as that capsule (other links have no geometry
  /// until setLinkMesh). Refers to `model`, which must outlive the world (see the class comment).
  explicit CollisionWorld(const arm::ArmModel& model);
  CollisionWorld(const arm::ArmModel& model, const Options& options);

  /// Gives `link` a triangle mesh in place of its capsule or of no geometry (for example an
  /// imported hand mesh). `X_LM` is the mesh frame in the link frame; it is baked into the
  /// vertices.
  /// @throws MeshError for a bad link index
  void setLinkMesh(int link, const TriMesh& mesh, const Eigen::Isometry3d& X_LM = Eigen::Isometry3d::Identity());
  /// Adds an object; returns its index.
  int addObject(std::string name, TriMesh mesh, const Eigen::Isometry3d& X_WO);
  void setObjectPose(int object, const Eigen::Isometry3d& X_WO);

  /// The model the world was built for.
  [[nodiscard]] const arm::ArmModel& model() const noexcept { return *model_; }
  [[nodiscard]] int numLinks() const noexcept { return static_cast<int>(links_.size()); }
  /// The link's geometry in the queries.
  [[nodiscard]] LinkShape linkShape(int link) const noexcept { return links_[static_cast<std::size_t>(link)].shape; }
  /// The link takes part in the queries (a capsule or a mesh).
  [[nodiscard]] bool hasLinkGeometry(int link) const noexcept { return linkShape(link) != LinkShape::kNone; }
  /// The link is queried as a triangle mesh (setLinkMesh).
  [[nodiscard]] bool hasLinkMesh(int link) const noexcept { return linkShape(link) == LinkShape::kMesh; }
  /// The link's capsule, link frame. Precondition: linkShape(link) == LinkShape::kCapsule.
  [[nodiscard]] const Capsule& linkCapsule(int link) const noexcept {
    return links_[static_cast<std::size_t>(link)].capsule;
  }
  /// Precondition: hasLinkMesh(link).
  [[nodiscard]] const TriMesh& linkMesh(int link) const noexcept {
    return links_[static_cast<std::size_t>(link)].mesh->mesh;
  }
  /// Precondition: hasLinkMesh(link).
  [[nodiscard]] const SnchTree& linkTree(int link) const noexcept {
    return links_[static_cast<std::size_t>(link)].mesh->tree;
  }
  /// Neighbour-rejection cones of the link's mesh (local descent). Precondition: hasLinkMesh(link).
  [[nodiscard]] const NeighbourCones& linkCones(int link) const noexcept {
    return links_[static_cast<std::size_t>(link)].mesh->cones;
  }
  [[nodiscard]] int numObjects() const noexcept { return static_cast<int>(objects_.size()); }
  [[nodiscard]] const CollisionObject& object(int i) const noexcept { return objects_[static_cast<std::size_t>(i)]; }
  /// Index of the object called `name`, or -1.
  [[nodiscard]] int objectIndex(std::string_view name) const noexcept;

  /// SNCH global search at the link frames of `fk` (a fresh SnchGlobalSearch; keep one
  /// SnchGlobalSearch alive instead to reuse its scratch). See GlobalSearch::search.
  void globalSearch(const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
                    std::vector<LocalMinimum>& out) const;

 private:
  struct LinkMesh {
    TriMesh mesh;
    SnchTree tree;
    NeighbourCones cones;
  };
  struct Link {
    LinkShape shape = LinkShape::kNone;
    Capsule capsule;
    std::shared_ptr<const LinkMesh> mesh;  // kMesh only
  };
  const arm::ArmModel* model_;  // not owned: outlives the world
  std::vector<Link> links_;
  std::vector<CollisionObject> objects_;
};

/// A global search strategy: every local minimum within the cutoff between every link with
/// geometry and every object at the configuration of `fk`, pruned with the endpoint radius. Implementations
/// are selectable at run time (SNCH here; a Bullet-based one in bullet_search.hpp).
class GlobalSearch {
 public:
  virtual ~GlobalSearch() = default;
  GlobalSearch() = default;
  GlobalSearch(const GlobalSearch&) = delete;
  GlobalSearch& operator=(const GlobalSearch&) = delete;
  /// @param fk forward kinematics of the configuration (link frames X_WL)
  /// @param cutoff_m cutoff length L [m]
  /// @param prune_radius_m endpoint pruning radius r [m] (0: no pruning)
  /// @param out replaced by the minima, sorted by (link, object, distance)
  virtual void search(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
                      std::vector<LocalMinimum>& out) = 0;
  [[nodiscard]] virtual std::string_view name() const noexcept = 0;
};

/// The SNCH global search (querySnchCapsule or querySnchPair on every link x object pair, then
/// pruneMinima).
class SnchGlobalSearch final : public GlobalSearch {
 public:
  void search(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
              std::vector<LocalMinimum>& out) override;
  [[nodiscard]] std::string_view name() const noexcept override { return "snch"; }
  /// Counters summed over the pairs of the last search.
  [[nodiscard]] const SnchQueryStats& lastStats() const noexcept { return stats_; }

 private:
  SnchQueryScratch scratch_;
  SnchQueryStats stats_;
};

/// Convenience: SnchGlobalSearch on a temporary scratch.
void globalSearch(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
                  std::vector<LocalMinimum>& out);

}  // namespace fullarm::haptics
