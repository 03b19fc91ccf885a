#pragma once
/// @file
/// Forward kinematics and Jacobians. All functions here are real-time safe.

#include <Eigen/Core>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Geometric Jacobian of a point: rows 0-2 linear velocity [m/s per rad/s], rows 3-5
/// angular velocity of the link [rad/s per rad/s]; one column per joint.
using PointJacobian = Eigen::Matrix<double, 6, Eigen::Dynamic, Eigen::ColMajor, 6, kMaxJoints>;

/// Real-time notes for every @rt function of the arm module: vectors must have size
/// model.numJoints() (checked by assert in debug builds only), and must be plain vectors or
/// blocks of them: passing an expression such as `q + dq` makes Eigen evaluate it into a heap
/// temporary before the call.
///
/// Link frames, joint axes z_i and origins o_i, link centres of mass and the hand pose, at q
/// (kept in data.q); counts one data.forward_kinematics_passes.
/// World frame W is the arm's root frame (the SL base, z up).
/// @param q joint angles [rad], size model.numJoints()
/// @rt
void computeForwardKinematics(const ArmModel& model, ArmData& data,
                              const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// Jacobian of the point p_W (world coordinates, rigidly attached to `link`) with respect to
/// all joints; columns of joints that do not move `link` are zero. Uses the frames of the
/// last computeForwardKinematics call.
/// @param link index of the link (0 .. n-1)
/// @param p_W  point in the world [m]
/// @param J    output, resized to 6 x n within its fixed capacity (never allocates)
/// @rt
void computePointJacobian(const ArmModel& model, const ArmData& data, int link, const Eigen::Vector3d& p_W,
                          PointJacobian& J) noexcept;

/// World coordinates of a point given in a link frame (after computeForwardKinematics).
/// @rt
[[nodiscard]] inline Eigen::Vector3d pointInWorld(const ArmData& data, int link, const Eigen::Vector3d& p_L) noexcept {
  return data.X_WL[static_cast<std::size_t>(link)] * p_L;
}

}  // namespace fullarm::arm
