#pragma once
/// @file
/// CollisionWorld: the arm's link meshes and the environment objects, each with its SNCH, and
/// the scene-level global search (every link with a mesh x every object, then pruning).

#include <Eigen/Geometry>
#include <cstdint>
#include <filesystem>
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
  struct Options {
    /// When set, addObject reads each object's hierarchy from this folder (hierarchyFromCache:
    /// keyed by the mesh's content hash and the build versions) and saves it there when it is
    /// missing or stale; otherwise it is built.
    std::filesystem::path hierarchy_cache_dir;
  };

  /// Takes every link whose geometry is a capsule as that capsule (other links have no geometry
  /// until setLinkMesh). Refers to `model`, which must outlive the world (see the class comment).
  explicit CollisionWorld(const arm::ArmModel& model);
  CollisionWorld(const arm::ArmModel& model, const Options& options);

  /// Gives `link` a triangle mesh in place of its capsule or of no geometry (for example an
  /// imported hand mesh). `X_LM` is the mesh frame in the link frame; it is baked into the
  /// vertices.
  /// @throws MeshError for a bad link index
  void setLinkMesh(int link, const TriMesh& mesh, const Eigen::Isometry3d& X_LM = Eigen::Isometry3d::Identity());
  /// Adds an object (its hierarchy built, or read from Options::hierarchy_cache_dir); returns its
  /// index.
  /// @throws std::runtime_error when the hierarchy cache folder cannot be written
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

  /// An identifier of the world's geometry, unique in the process: a new world, a copy and
  /// every setLinkMesh or addObject get a new one (setObjectPose does not: poses are inputs of
  /// every query). A coherent search keeps what it proved for one revision only.
  [[nodiscard]] std::uint64_t revision() const noexcept { return revision_.value; }

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
  // A process-unique number that copies do not share.
  struct Revision {
    std::uint64_t value = next();
    Revision() = default;
    Revision(const Revision& /*other*/) noexcept : value(next()) {}
    Revision& operator=(const Revision& /*other*/) noexcept {
      value = next();
      return *this;
    }
    static std::uint64_t next() noexcept;
  };
  const arm::ArmModel* model_;  // not owned: outlives the world
  Options options_;
  std::vector<Link> links_;
  std::vector<CollisionObject> objects_;
  Revision revision_;
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

/// How SnchGlobalSearch runs; neither option changes its result (the minima, their order and
/// their bits), only its time.
struct SnchSearchOptions {
  /// Threads that run one search: the calling thread and threads - 1 helper threads that the
  /// search object starts once and keeps (>= 1). The link x object pairs are shared out, the
  /// costliest first (by the previous search's times), and their minima joined in pair order.
  int threads = 1;
  /// Start every capsule link x object pair from what the previous search of this object proved
  /// about it (querySnchCapsuleCoherent: the front of its traversal with distance bounds), as
  /// long as the world's revision and the cutoff are the same.
  bool coherent = true;
};

/// The SNCH global search: querySnchCapsule (querySnchCapsuleCoherent) or querySnchPair on every
/// link x object pair, each pair's minima in the canonical order of mergeDuplicateMinima, the
/// pairs in (link, object) order, then pruneMinima (whose order-dependent acceptance thus sees
/// the same sequence whatever the thread count or the coherence).
class SnchGlobalSearch final : public GlobalSearch {
 public:
  /// @throws std::invalid_argument when options.threads < 1
  explicit SnchGlobalSearch(const SnchSearchOptions& options = {});
  ~SnchGlobalSearch() override;
  void search(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
              std::vector<LocalMinimum>& out) override;
  [[nodiscard]] std::string_view name() const noexcept override { return "snch"; }
  /// Counters summed over the pairs of the last search.
  [[nodiscard]] const SnchQueryStats& lastStats() const noexcept { return stats_; }
  [[nodiscard]] const SnchSearchOptions& options() const noexcept { return options_; }

 private:
  struct Impl;
  SnchSearchOptions options_;
  std::unique_ptr<Impl> impl_;
  SnchQueryStats stats_;
};

/// Convenience: SnchGlobalSearch on a temporary scratch.
void globalSearch(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
                  std::vector<LocalMinimum>& out);

}  // namespace fullarm::haptics
