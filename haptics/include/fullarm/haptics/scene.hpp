#pragma once
/// @file
/// Scene: the environment objects (an imported mesh or a primitive solid, each with a pose),
/// where the arm's shoulder stands, and named postures, read from a strict YAML file in
/// `scenes/` (schema in docs/haptics.md, section "Scene files").
///
/// Frames: S is the scene frame (z up, metres). The arm model's world frame W (the frame of
/// forward kinematics, gravity along -z) is placed in S by the shoulder position and a heading
/// about z only, so gravity keeps pointing down. Object meshes are in their object frame O,
/// placed by X_SO.

#include <Eigen/Geometry>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// One environment object.
struct SceneObject {
  std::string name;                 ///< unique within the scene
  std::string shape;                ///< human-readable shape, e.g. "box 0.3 x 0.01 x 1.1 m" or a mesh file name
  std::filesystem::path mesh_file;  ///< absolute path of the imported file; empty for a primitive
  TriMesh mesh;                     ///< in the object frame O [m]
  Eigen::Isometry3d X_SO = Eigen::Isometry3d::Identity();  ///< object pose in the scene
};

/// A named arm posture stored with the scene (for example the reach the scene was designed for).
struct ScenePosture {
  std::string name;
  /// Joint angles [rad]; may hold fewer values than the model has joints (the rest take the
  /// model's default posture, see scenePosture()).
  Eigen::VectorXd q_rad;
};

/// A task target named by the scene: where the hand grasps an object and which way it pushes
/// there (the accessibility question: can the arm get the hand here, and push how hard).
struct SceneTarget {
  std::string name;    ///< unique within the scene
  std::string object;  ///< the object grasped (a scene object's name)
  /// The hand point (the arm model's tool point) at the grasp, scene frame [m].
  Eigen::Vector3d position_S_m = Eigen::Vector3d::Zero();
  /// Unit: the hand's pointing axis at the grasp (the tool link's x axis), scene frame.
  Eigen::Vector3d approach_S = Eigen::Vector3d::UnitY();
  /// Unit: the direction the hand pushes on the object, scene frame.
  Eigen::Vector3d push_S = Eigen::Vector3d::UnitY();
};

/// Farthest a target's hand point may lie from the surface of its object [m]: a grasp is on
/// the object (the hand point sits inside the hand, a few centimetres from the skin).
inline constexpr double kTargetMaxObjectDistance_m = 0.08;

/// A loaded scene. Treat as constant after loading.
struct Scene {
  std::string name;
  std::string description;
  std::filesystem::path source;  ///< the YAML file (empty when parsed from text without one)
  /// Shoulder centre (origin of the arm's DH frame 0) in the scene [m].
  Eigen::Vector3d shoulder_S_m = Eigen::Vector3d::Zero();
  /// Rotation of the arm's world frame about the scene's z axis [rad] (0: W axes = S axes).
  double heading_rad = 0.0;
  std::vector<SceneObject> objects;
  std::vector<ScenePosture> postures;
  std::vector<SceneTarget> targets;  ///< optional key `targets`, in file order
  /// Folder where the objects' hierarchies are saved and reloaded (hierarchy_cache.hpp), from
  /// the optional key `hierarchy_cache` (relative to the scene file); empty: none.
  std::filesystem::path hierarchy_cache_dir;

  /// Index of the object called `name`, or -1.
  [[nodiscard]] int objectIndex(std::string_view name) const noexcept;
  /// The posture called `name`, or nullptr.
  [[nodiscard]] const ScenePosture* posture(std::string_view name) const noexcept;
  /// The target called `name`, or nullptr.
  [[nodiscard]] const SceneTarget* target(std::string_view name) const noexcept;
  /// Sum of the objects' triangle counts.
  [[nodiscard]] long numTriangles() const noexcept;
};

/// Reads a scene file. Mesh files are resolved relative to the scene file's folder.
/// @throws core::ConfigError naming the file, the key path and what was expected, for YAML
///   errors, unknown or missing keys, bad values, duplicate object names, meshes that
///   cannot be imported (the MeshError text is included), and targets that name an unknown
///   object, have a zero direction or lie farther than kTargetMaxObjectDistance_m from their
///   object's surface.
[[nodiscard]] Scene loadScene(const std::filesystem::path& file);

/// Same from text. `file` names the source in errors; relative mesh paths are resolved
/// against `file`'s folder (the current directory when `file` is empty).
[[nodiscard]] Scene parseScene(std::string_view yaml_text, const std::filesystem::path& file);

/// Pose of the arm model's world frame W in the scene: the translation that puts the model's
/// DH frame 0 origin (model.X_WB) on the scene's shoulder, and the heading about z.
[[nodiscard]] Eigen::Isometry3d armBasePose(const Scene& scene, const arm::ArmModel& model);

/// A CollisionWorld with the model's link geometry and every scene object at
/// X_WO = X_SW^-1 X_SO (object indices equal scene object indices). The objects' hierarchies
/// come from `options.hierarchy_cache_dir`, else from the scene's hierarchy_cache_dir, when
/// either is set (saved there when missing or stale).
/// @throws std::runtime_error when the hierarchy cache folder cannot be written
[[nodiscard]] CollisionWorld makeCollisionWorld(const Scene& scene, const arm::ArmModel& model,
                                                const CollisionWorld::Options& options = {});

/// The full joint vector (size model.numJoints()) of the scene posture called `name`: its
/// values, then the model's default posture for the joints it does not list.
/// @throws core::ConfigError (file = scene.source, key `arm.postures[i].q_rad`) if there is no
///   such posture, it has more values than the model has joints, or a value lies outside its
///   joint's range.
[[nodiscard]] Eigen::VectorXd scenePosture(const Scene& scene, std::string_view name, const arm::ArmModel& model);

}  // namespace fullarm::haptics
