#pragma once
/// @file
/// ArmModel: the constant description of the DTS master arm (kinematic tree, limits,
/// inertias, collision geometry, actuator geometry, sensor calibration).
///
/// Convention: modified (Craig) Denavit-Hartenberg for the arm chain,
/// T_{i-1,i} = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(theta_i) Tz(d_i), theta_i = q_i + theta_offset_i.
/// Link frame i therefore lies on joint axis i (its +z) and moves with joint i. Hand joints
/// hang off a parent link with a fixed origin transform and also turn about their own +z.
/// Every link quantity (centre of mass, inertia, geometry) is expressed in its link frame.

#include <Eigen/Geometry>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/sensors.hpp"

namespace fullarm::arm {

/// Upper bound on joints (7 arm + 3 hand); lets the 1 kHz path use fixed-capacity storage.
inline constexpr int kMaxJoints = 10;

/// Modified-DH row of one arm joint, in the units of the YAML (lengths m, angles rad).
struct DhParameters {
  double alpha_rad = 0.0;         ///< twist alpha_{i-1} about the previous x axis
  double a_m = 0.0;               ///< length a_{i-1} along the previous x axis
  double d_m = 0.0;               ///< offset d_i along this joint's z axis
  double theta_offset_rad = 0.0;  ///< theta_i = q_i + theta_offset_rad
};

/// Joint range and actuator capability.
struct JointLimits {
  double min_rad = 0.0;
  double max_rad = 0.0;
  double velocity_radps = 0.0;  ///< magnitude
  double torque_nm = 0.0;       ///< magnitude of the torque command saturation
};

/// Collision/visual geometry of one link, in its link frame.
struct LinkGeometry {
  enum class Type { kNone, kCapsule, kMesh };
  Type type = Type::kNone;
  double radius_m = 0.0;                                   ///< capsule radius
  Eigen::Vector3d from_m = Eigen::Vector3d::Zero();        ///< capsule segment start, link frame
  Eigen::Vector3d to_m = Eigen::Vector3d::Zero();          ///< capsule segment end, link frame
  std::filesystem::path mesh_file;                         ///< absolute path of a mesh file
  double mesh_scale = 1.0;                                 ///< mesh units to metres
  Eigen::Isometry3d X_LM = Eigen::Isometry3d::Identity();  ///< mesh pose in the link frame
};

/// Mass properties of one link. The inertia is about the centre of mass, in the link frame.
struct LinkInertial {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  Eigen::Matrix3d inertia_com_kgm2 = Eigen::Matrix3d::Zero();
};

/// How the joint is driven. A linear actuator is a hydraulic cylinder on a lever: moment arm
/// r from the joint axis to the rod attachment, mount distance d from the joint axis to the
/// cylinder's fixed mount. The lever angle is phi = q + lever_angle_offset_rad (the angle
/// between the lever and the joint-to-mount line); the moment arm is largest (= r) at
/// phi = acos(r/d). See actuator.hpp.
struct ActuatorGeometry {
  enum class Type { kRotary, kLinear };
  Type type = Type::kRotary;
  double moment_arm_m = 0.0;
  double mount_distance_m = 0.0;
  double lever_angle_offset_rad = 0.0;
};

/// One joint and the link it moves.
struct Joint {
  std::string name;
  int parent = -1;  ///< index of the parent joint/link; -1 for the base
  bool is_hand = false;
  std::optional<DhParameters> dh;  ///< set for arm-chain joints
  /// Fixed transform from the parent link frame to this link frame at q = 0; the link frame
  /// then turns by Rz(q) about its own +z: X_PL(q) = X_PL0 * Rz(q).
  Eigen::Isometry3d X_PL0 = Eigen::Isometry3d::Identity();
  JointLimits limits;
  double default_rad = 0.0;
  LinkInertial inertial;
  LinkGeometry geometry;
  ActuatorGeometry actuator;
  PotentiometerCalibration potentiometer;
  TorqueSensorCalibration torque_sensor;
  TorqueCommandCalibration torque_command;
};

/// The whole arm. Treat as constant after validateArmModel(); algorithms take it by const&.
struct ArmModel {
  std::string name;
  std::filesystem::path source;                            ///< file it was loaded from (empty if built in code)
  Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();  ///< world -> DH frame 0
  Eigen::Vector3d gravity_W_mps2{0.0, 0.0, -9.81};
  std::vector<Joint> joints;  ///< arm chain first, then hand joints; parents precede children
  int tool_link = -1;         ///< link that carries the hand point
  Eigen::Isometry3d X_LT = Eigen::Isometry3d::Identity();  ///< hand point in the tool link frame
  int upper_arm_joint = -1;                                ///< joint whose DH d is the upper-arm length (-1: none)
  int forearm_joint = -1;                                  ///< joint whose DH d is the forearm length (-1: none)

  [[nodiscard]] int numJoints() const noexcept { return static_cast<int>(joints.size()); }
  /// Number of arm-chain (non-hand) joints.
  [[nodiscard]] int numArmJoints() const noexcept;
  /// Index of the joint called `name`, or -1.
  [[nodiscard]] int jointIndex(std::string_view name) const noexcept;
  [[nodiscard]] Eigen::VectorXd defaultPosture() const;
  [[nodiscard]] Eigen::VectorXd lowerLimits() const;
  [[nodiscard]] Eigen::VectorXd upperLimits() const;
  [[nodiscard]] double totalMass() const noexcept;
};

/// Fixed transform of a modified-DH row: Rx(alpha) Tx(a) Rz(theta_offset) Tz(d).
[[nodiscard]] Eigen::Isometry3d dhTransform(const DhParameters& dh);

/// Rotation from roll-pitch-yaw (URDF convention): R = Rz(yaw) Ry(pitch) Rx(roll).
[[nodiscard]] Eigen::Matrix3d rotationFromRpy(double roll_rad, double pitch_rad, double yaw_rad);

/// Checks everything the loader checks (limits, physical consistency of every inertia,
/// geometry, actuator and sensor calibration, tree order).
/// @throws core::ConfigError naming `model.source` and the key path of the first problem.
void validateArmModel(const ArmModel& model);

/// Checks that an inertia about the centre of mass is physically valid for `mass_kg`:
/// symmetric, positive definite (or zero for a massless link), principal moments obeying
/// the triangle inequality. Returns an empty string when valid, else what is wrong.
[[nodiscard]] std::string checkInertia(double mass_kg, const Eigen::Matrix3d& inertia_com_kgm2);

/// True when joint `joint` moves link `link` (it is the link's joint or an ancestor).
/// @rt
[[nodiscard]] bool jointMovesLink(const ArmModel& model, int joint, int link) noexcept;

}  // namespace fullarm::arm
