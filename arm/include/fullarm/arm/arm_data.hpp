#pragma once
/// @file
/// ArmData: preallocated scratch and results for the arm algorithms (Model/Data split).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cstdint>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/rigid_body_dynamics.hpp"

namespace fullarm::arm {

/// Everything the algorithms of kinematics.hpp and dynamics.hpp write. Sized once for one
/// model by the constructor (which also records the model's joint tree); no algorithm resizes
/// it, so the @rt functions never allocate. Indices follow ArmModel::joints.
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

  // Rigid-body dynamics (dynamics.hpp): the spatial algorithm of rigid_body_dynamics.hpp on the
  // unreduced arm, every joint a body.
  Eigen::VectorXd tau;           ///< inverse dynamics result [N m]
  Eigen::VectorXd tau_coriolis;  ///< C(q, qd) qd [N m]
  Eigen::MatrixXd mass_matrix;   ///< M(q) [kg m^2], n x n
  RigidBodyTree tree;            ///< the model's joint tree (parents, order, supports), set by the constructor
  RigidBodyData bodies;          ///< spatial kinematics and Newton-Euler scratch
  BodyVector body_vector;        ///< scratch: qd, qdd or a result over the bodies
  BodyMatrix body_matrix;        ///< scratch: M over the bodies
};

}  // namespace fullarm::arm
