#pragma once
/// @file
/// Inverse kinematics of the arm chain to a grasp pose, over the arm's redundancy: the seven
/// arm joints against six pose constraints leave the elbow's swivel angle about the
/// shoulder-wrist line free, and the grasp leaves the hand's roll about its pointing axis free.
/// Each goal configuration is a damped-least-squares solve of the square system (hand pose,
/// swivel angle) with the joint limits enforced by clamping; a sweep over swivel x roll gives the
/// goal set (and, when none of them is valid, the certificate of an unreachable target).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <vector>

#include "fullarm/accessibility/target.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"

namespace fullarm::accessibility {

/// Settings of one solve and of the sweep.
struct IkOptions {
  int swivel_samples = 72;    ///< swivel angles over [-pi, pi) (5 degree steps)
  int roll_samples = 12;      ///< hand rolls about the pointing axis over [-pi, pi) (30 degree steps)
  int max_iterations = 200;   ///< damped-least-squares steps per solve
  double damping = 0.02;      ///< lambda of (J J^T + lambda^2 I)
  double max_step_rad = 0.2;  ///< largest joint step per iteration [rad]
  double position_tolerance_m = 1e-4;
  double angle_tolerance_rad = 1e-3;  ///< hand orientation and swivel angle
};

/// Swivel angle of the elbow [rad]: the angle of the elbow (origin of joint 4) about the line
/// from the shoulder (DH frame 0) to the wrist (origin of joint 6), 0 with the elbow straight
/// below that line (the world's -z projected), positive counter-clockwise about the line's
/// direction. Reads the link origins of the last forward kinematics.
[[nodiscard]] double swivelAngle(const arm::ArmData& fk);

/// One goal configuration.
struct IkSolution {
  Eigen::VectorXd q_rad;          ///< full configuration (hand joints at their defaults)
  bool converged = false;         ///< within every tolerance, joint limits respected
  double position_error_m = 0.0;  ///< hand point to target [m]
  double angle_error_rad = 0.0;   ///< hand orientation error [rad]
  double swivel_error_rad = 0.0;  ///< swivel angle error [rad]
  int iterations = 0;
  double swivel_rad = 0.0;  ///< the swivel angle asked for
  double roll_rad = 0.0;    ///< the hand roll asked for
};

/// Solves for the configuration whose hand point is at `position_W_m` with link-frame
/// orientation `R_W` (tool link) and swivel angle `swivel_rad`, from `q_seed` (full size).
/// @throws std::invalid_argument for a seed of the wrong size
[[nodiscard]] IkSolution solveIk(const arm::ArmModel& model, arm::ArmData& fk, const Eigen::Vector3d& position_W_m,
                                 const Eigen::Matrix3d& R_W, double swivel_rad, const Eigen::VectorXd& q_seed,
                                 const IkOptions& options);

/// The converged solutions over the sweep of swivel (options.swivel_samples) x roll
/// (options.roll_samples), each seeded from the previous swivel's solution (continuation), the
/// first from `q_seed` and from the model's default posture. Order: roll-major, then swivel.
[[nodiscard]] std::vector<IkSolution> sweepGoalConfigurations(const arm::ArmModel& model, const GraspTarget& target,
                                                              const Eigen::VectorXd& q_seed, const IkOptions& options);

}  // namespace fullarm::accessibility
