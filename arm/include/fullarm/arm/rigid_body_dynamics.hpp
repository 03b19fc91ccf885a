#pragma once
/// @file
/// The rigid-body dynamics of the arm: spatial Newton-Euler (RNEA), composite rigid bodies
/// (CRBA) and the analytic derivatives of the inverse dynamics, on a tree of rigid bodies.
///
/// The tree is the arm with some joints free (the "active" joints) and the others locked: every
/// locked joint (the hand joints, and the arm joints a single-joint or partial plant does not
/// drive) is rigid, so its link is merged once, at reduceArmModel(), into the body of the
/// nearest active ancestor (parallel-axis theorem), or dropped if no active joint moves it.
/// The algorithms then run over n bodies in spatial (6-D) vectors expressed at the world origin
/// (Featherstone, Rigid Body Dynamics Algorithms, 2008, ch. 2 and 5), which makes the
/// derivatives short:
///
///   motion  V = (omega, v_O)  (v_O: velocity of the body point at the world origin)
///   force   F = (n_O, f)      (n_O: moment about the world origin)
///   joint b: s_b = (z_b, o_b x z_b);  V_b = V_p + s_b qd_b;  A_b = A_p + s_b qdd_b + V_b x s_b qd_b
///   body force F_b = I_b A_b + V_b x* I_b V_b;  tau_b = s_b . sum_{k in subtree(b)} F_k
///
/// with A_ground = (0, -g), so gravity enters as an inertial force (reports/equations.md R1-R4).
/// Model/Data split: RigidBodyModel is constant after reduceArmModel(); RigidBodyData holds
/// all scratch in fixed-capacity storage, so every compute function is @rt (no allocation).

#include <Eigen/Core>
#include <array>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Largest number of bodies of a rigid-body tree.
inline constexpr int kMaxBodies = kMaxJoints;

/// Fixed-capacity square matrix and vector over the bodies (no heap).
using BodyMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxBodies, kMaxBodies>;
using BodyVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxBodies, 1>;

/// The topology of a tree of n bodies, each turning about its own joint: what the recursions
/// need besides the kinematics.
struct RigidBodyTree {
  int n = 0;
  /// Body k's parent body, -1 for the ground.
  std::array<int, kMaxBodies> parent{};
  /// Bodies in an order where every parent precedes its children.
  std::array<int, kMaxBodies> order{};
  /// supports[k][b]: joint k moves body b (k is b or one of its ancestors).
  std::array<std::array<bool, kMaxBodies>, kMaxBodies> supports{};
};

/// The arm with only the active joints free. Body k turns about active joint k (the order of
/// the `active` list given to reduceArmModel, which need not be topological).
struct RigidBodyModel {
  RigidBodyTree tree;
  /// Body k's frame at q_k = 0 in its parent body's frame (the world for the ground):
  /// X_PB(q) = (R0, p0) Rz(q), the link frame of the joint's arm-model link.
  std::array<Eigen::Matrix3d, kMaxBodies> rotation0{};
  std::array<Eigen::Vector3d, kMaxBodies> translation0_m{};
  /// Merged mass properties in the body frame (inertia about the merged centre of mass).
  std::array<double, kMaxBodies> mass_kg{};
  std::array<Eigen::Vector3d, kMaxBodies> com_m{};
  std::array<Eigen::Matrix3d, kMaxBodies> inertia_com_kgm2{};
  Eigen::Vector3d gravity_W_mps2 = Eigen::Vector3d(0.0, 0.0, -9.81);
};

/// A spatial motion vector (omega, v_O) or force vector (n_O, f), world coordinates.
struct SpatialVector {
  Eigen::Vector3d top = Eigen::Vector3d::Zero();
  Eigen::Vector3d bottom = Eigen::Vector3d::Zero();
};

/// Everything the rigid-body algorithms write, fixed capacity.
struct RigidBodyData {
  // Kinematics at (q, qd) (computeRigidBodyKinematics).
  std::array<Eigen::Matrix3d, kMaxBodies> R_WB{};  ///< body orientations
  std::array<Eigen::Vector3d, kMaxBodies> o_W{};   ///< joint origins [m]
  std::array<SpatialVector, kMaxBodies> s{};       ///< joint axes (z, o x z)
  std::array<SpatialVector, kMaxBodies> V{};       ///< body velocities
  std::array<double, kMaxBodies> qd{};             ///< joint velocities [rad/s]
  std::array<double, kMaxBodies> sin_q{};          ///< sin q of each joint (shared with the actuators)
  std::array<double, kMaxBodies> cos_q{};          ///< cos q
  /// Acceleration of the ground, (0, -g): gravity as an inertial force.
  SpatialVector ground_accel{Eigen::Vector3d::Zero(), Eigen::Vector3d(0.0, 0.0, 9.81)};
  // Spatial inertias about the world origin: mass, first moment m c, rotational inertia.
  std::array<double, kMaxBodies> mass_kg{};
  std::array<Eigen::Vector3d, kMaxBodies> first_moment_kgm{};
  std::array<Eigen::Matrix3d, kMaxBodies> inertia_O_kgm2{};
  // Newton-Euler at some qdd (computeRigidBodyInverseDynamics).
  std::array<SpatialVector, kMaxBodies> A{};      ///< body accelerations
  std::array<SpatialVector, kMaxBodies> IV{};     ///< body momenta I V
  std::array<SpatialVector, kMaxBodies> IA{};     ///< I A
  std::array<SpatialVector, kMaxBodies> F{};      ///< body inertial forces I A + V x* I V
  std::array<SpatialVector, kMaxBodies> F_tot{};  ///< subtree force through each joint
};

/// Forward kinematics, world inertias, body velocities and the ground acceleration at (q, qd)
/// (size n each). @rt
void computeRigidBodyKinematics(const RigidBodyModel& model, RigidBodyData& data, const BodyVector& q,
                                const BodyVector& qd) noexcept;

/// Inverse dynamics tau = M(q) qdd + C(q, qd) qd + g(q) at the kinematics of the last
/// computeRigidBodyKinematics (Newton-Euler, R1-R4). @rt
void computeRigidBodyInverseDynamics(const RigidBodyTree& tree, RigidBodyData& data, const BodyVector& qdd,
                                     BodyVector& tau) noexcept;

/// Gravity torques g(q) = ID(q, 0, 0): Newton-Euler at rest (R3-R4 with V = 0 and every body
/// accelerating with the ground), which needs only the masses, first moments and joint axes of
/// the last kinematics: F_b = (h_b x (-g), -m_b g), tau_b = s_b . sum_{k in subtree(b)} F_k. @rt
void computeRigidBodyGravity(const RigidBodyTree& tree, const RigidBodyData& data, BodyVector& tau) noexcept;

/// Joint-space inertia M(q) (n x n) at the last kinematics, by composite rigid bodies:
/// M_ij = s_i . (I^C_j s_j) for i an ancestor of (or equal to) j (R5). @rt
void computeRigidBodyMassMatrix(const RigidBodyTree& tree, const RigidBodyData& data, BodyMatrix& mass) noexcept;

/// Analytic partial derivatives of the inverse dynamics ID(q, qd, qdd) with respect to q and
/// qd (n x n each) at the last kinematics and `qdd` (R6-R8 collected into composite subtree
/// quantities, R13: O(n) 6 x 6 work and one dot product per entry). Runs the Newton-Euler pass
/// at qdd itself (tau is left in `tau`). @rt
void computeRigidBodyInverseDynamicsDerivatives(const RigidBodyTree& tree, RigidBodyData& data, const BodyVector& qdd,
                                                BodyVector& tau, BodyMatrix& dtau_dq, BodyMatrix& dtau_dqd) noexcept;

/// The same derivatives body by body (R6-R8: for each joint, every body it moves; O(n^2) spatial
/// operations): the first implementation, kept as an independent check of the composite form. @rt
void computeRigidBodyInverseDynamicsDerivativesPerBody(const RigidBodyTree& tree, RigidBodyData& data,
                                                       const BodyVector& qdd, BodyVector& tau, BodyMatrix& dtau_dq,
                                                       BodyMatrix& dtau_dqd) noexcept;

/// World position of a body point after computeRigidBodyKinematics.
[[nodiscard]] inline Eigen::Vector3d bodyPointInWorld(const RigidBodyData& data, int body,
                                                      const Eigen::Vector3d& p_B) noexcept {
  return data.o_W[static_cast<std::size_t>(body)] + data.R_WB[static_cast<std::size_t>(body)] * p_B;
}

}  // namespace fullarm::arm
