#pragma once
/// @file
/// ArmData: preallocated scratch and results for the arm algorithms (Model/Data split).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Everything the algorithms of kinematics.hpp and dynamics.hpp write. Sized once for one
/// model by the constructor; no algorithm resizes it, so the @rt functions never allocate.
/// Indices follow ArmModel::joints.
struct ArmData {
  explicit ArmData(const ArmModel& model);

  // Forward kinematics (computeForwardKinematics).
  Eigen::VectorXd q;                                       ///< configuration of the last FK [rad], size n
  std::vector<Eigen::Isometry3d> X_WL;                     ///< link frames in the world
  std::vector<Eigen::Vector3d> z_W;                        ///< joint axes (unit) in the world
  std::vector<Eigen::Vector3d> o_W;                        ///< joint origins (link frame origins) in the world [m]
  std::vector<Eigen::Vector3d> com_W;                      ///< link centres of mass in the world [m]
  Eigen::Isometry3d X_WT = Eigen::Isometry3d::Identity();  ///< hand point (tool) pose

  // Gravity (computeGravityTorquesAtKinematics).
  Eigen::VectorXd tau_gravity;  ///< dV/dq: torque that holds the arm against gravity [N m]

  // Pass counters: how often the configuration's kinematics and gravity were computed into
  // this object (incremented by computeForwardKinematics and computeGravityTorquesAtKinematics,
  // never reset by them). A tick that composes the arm's pieces checks with them that each is
  // computed once.
  std::uint64_t forward_kinematics_passes = 0;
  std::uint64_t gravity_passes = 0;

  // Recursive Newton-Euler (dynamics.hpp).
  Eigen::VectorXd tau;           ///< inverse dynamics result [N m]
  Eigen::VectorXd tau_coriolis;  ///< C(q, qd) qd [N m]
  Eigen::MatrixXd mass_matrix;   ///< M(q) [kg m^2], n x n
  Eigen::VectorXd qdd_unit;      ///< scratch for mass-matrix columns

  // Per-link scratch, world frame.
  std::vector<Eigen::Vector3d> omega;         ///< angular velocity [rad/s]
  std::vector<Eigen::Vector3d> omega_dot;     ///< angular acceleration [rad/s^2]
  std::vector<Eigen::Vector3d> accel_origin;  ///< linear acceleration of the link origin [m/s^2]
  std::vector<Eigen::Vector3d> force;         ///< force transmitted through the joint [N]
  std::vector<Eigen::Vector3d> moment;        ///< moment about the joint origin [N m]
  std::vector<Eigen::Vector3d> mass_moment;   ///< subtree first moment sum(m c) [kg m]
  std::vector<double> subtree_mass_kg;
  std::vector<Eigen::Matrix3d> inertia_W;  ///< link inertia about its COM in the world
};

}  // namespace fullarm::arm
