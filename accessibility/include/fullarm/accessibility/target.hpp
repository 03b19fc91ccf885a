#pragma once
/// @file
/// A scene's grasp target in the arm's world frame W: the pose the hand must take (its point on
/// the object, its pointing axis) and the push direction, with the goal orientations the hand
/// may take there (the roll about the pointing axis is free).

#include <Eigen/Geometry>
#include <string>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::accessibility {

/// A grasp target in the arm's world frame W.
struct GraspTarget {
  std::string name;                                        ///< the scene target's name
  std::string object;                                      ///< the object grasped
  int object_index = -1;                                   ///< its index in the scene (and collision world)
  Eigen::Vector3d position_W_m = Eigen::Vector3d::Zero();  ///< the hand point at the grasp [m]
  Eigen::Vector3d approach_W = Eigen::Vector3d::UnitX();   ///< unit: the hand's pointing axis
  Eigen::Vector3d push_W = Eigen::Vector3d::UnitX();       ///< unit: the push on the object
};

/// The scene target called `name` (empty: the scene's first target) in the arm's world frame
/// (haptics::armBasePose places W in the scene).
/// @throws core::ConfigError (file = scene.source, key `targets`) when the scene has no target or
///   none of that name (the message lists the names)
[[nodiscard]] GraspTarget resolveTarget(const haptics::Scene& scene, const arm::ArmModel& model, std::string_view name);

/// Orientation of the hand's link frame at the grasp with roll `roll_rad` about the pointing
/// axis: x = approach_W; roll 0 puts y in the plane of x and the world's vertical (y the
/// horizontal perpendicular to x, turning counter-clockwise seen from above; for a vertical
/// approach, the world's y axis projected), and the roll turns y and z about x.
[[nodiscard]] Eigen::Matrix3d graspOrientation(const GraspTarget& target, double roll_rad);

}  // namespace fullarm::accessibility
