#pragma once
/// @file
/// Rigid-body dynamics of the arm reduced to the plant's active joints, with analytic
/// derivatives of the inverse dynamics.
///
/// Every locked joint (the hand joints, and the arm joints a single-joint or partial plant
/// does not drive) is rigid, so its link is merged once, at reduceArmModel(), into the body of
/// the nearest active ancestor (parallel-axis theorem), or dropped if no active joint moves it.
/// The 1 kHz path then runs Newton-Euler over n active bodies instead of every link of
/// fullarm::arm, in spatial (6-D) vectors expressed at the world origin (Featherstone, Rigid
/// Body Dynamics Algorithms, 2008, ch. 2 and 5), which makes the derivatives short:
///
///   motion  V = (omega, v_O)  (v_O: velocity of the body point at the world origin)
///   force   F = (n_O, f)      (n_O: moment about the world origin)
///   joint b: s_b = (z_b, o_b x z_b);  V_b = V_p + s_b qd_b;  A_b = A_p + s_b qdd_b + V_b x s_b qd_b
///   body force F_b = I_b A_b + V_b x* I_b V_b;  tau_b = s_b . sum_{k in subtree(b)} F_k
///
/// with A_ground = (0, -g), so gravity enters as an inertial force (reports/equations.md R1-R4).
/// Model/Data split: ReducedArmModel is constant after reduceArmModel(); ReducedArmData holds
/// all scratch in fixed-capacity storage, so every compute function is @rt (no allocation).

#include <Eigen/Core>
#include <array>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::plant {

/// Largest number of bodies of a reduced arm.
inline constexpr int kMaxReducedBodies = arm::kMaxJoints;

/// Fixed-capacity square matrix and vector over the bodies (no heap).
using ReducedMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxReducedBodies, kMaxReducedBodies>;
using ReducedVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxReducedBodies, 1>;

/// The arm with only the active joints free. Body k turns about active joint k (the order of
/// the `active` list given to reduceArmModel, which need not be topological).
struct ReducedArmModel {
  int n = 0;
  /// Body k's parent body, -1 for the ground.
  std::array<int, kMaxReducedBodies> parent{};
  /// Bodies in an order where every parent precedes its children.
  std::array<int, kMaxReducedBodies> order{};
  /// supports[k][b]: active joint k moves body b (k is b or one of its ancestors).
  std::array<std::array<bool, kMaxReducedBodies>, kMaxReducedBodies> supports{};
  /// Body k's frame at q_k = 0 in its parent body's frame (the world for the ground):
  /// X_PB(q) = (R0, p0) Rz(q), the link frame of the joint's arm-model link.
  std::array<Eigen::Matrix3d, kMaxReducedBodies> rotation0{};
  std::array<Eigen::Vector3d, kMaxReducedBodies> translation0_m{};
  /// Merged mass properties in the body frame (inertia about the merged centre of mass).
  std::array<double, kMaxReducedBodies> mass_kg{};
  std::array<Eigen::Vector3d, kMaxReducedBodies> com_m{};
  std::array<Eigen::Matrix3d, kMaxReducedBodies> inertia_com_kgm2{};
  Eigen::Vector3d gravity_W_mps2 = Eigen::Vector3d(0.0, 0.0, -9.81);
};

/// Builds the reduced model: active[k] is the arm-model index of body k's joint; locked joints
/// stay at `posture` (size model.numJoints()). Links that no active joint moves are dropped
/// (they cannot load an active joint).
/// @throws std::invalid_argument for an empty, repeated or out-of-range active list or a
/// posture of the wrong size.
[[nodiscard]] ReducedArmModel reduceArmModel(const arm::ArmModel& model, const std::vector<int>& active,
                                             const Eigen::VectorXd& posture);

/// Body k's point `p_L` given in arm-model link `link`'s frame, in body frame coordinates, and the
/// body that carries it (-1: no active joint moves that link; the point is then fixed).
struct ReducedPoint {
  int body = -1;
  Eigen::Vector3d p_B = Eigen::Vector3d::Zero();
};
/// Locates an arm-model link point on the reduced model (same `active` and `posture` as
/// reduceArmModel). @throws std::invalid_argument for a bad link index.
[[nodiscard]] ReducedPoint reducePoint(const arm::ArmModel& model, const std::vector<int>& active,
                                       const Eigen::VectorXd& posture, int link, const Eigen::Vector3d& p_L);

/// A spatial motion vector (omega, v_O) or force vector (n_O, f), world coordinates.
struct SpatialVector {
  Eigen::Vector3d top = Eigen::Vector3d::Zero();
  Eigen::Vector3d bottom = Eigen::Vector3d::Zero();
};

/// Everything the reduced algorithms write, fixed capacity.
struct ReducedArmData {
  // Kinematics at (q, qd) (computeReducedKinematics).
  std::array<Eigen::Matrix3d, kMaxReducedBodies> R_WB{};  ///< body orientations
  std::array<Eigen::Vector3d, kMaxReducedBodies> o_W{};   ///< joint origins [m]
  std::array<SpatialVector, kMaxReducedBodies> s{};       ///< joint axes (z, o x z)
  std::array<SpatialVector, kMaxReducedBodies> V{};       ///< body velocities
  std::array<double, kMaxReducedBodies> qd{};             ///< joint velocities [rad/s]
  std::array<double, kMaxReducedBodies> sin_q{};          ///< sin q of each joint (shared with the actuators)
  std::array<double, kMaxReducedBodies> cos_q{};          ///< cos q
  // Spatial inertias about the world origin: mass, first moment m c, rotational inertia.
  std::array<double, kMaxReducedBodies> mass_kg{};
  std::array<Eigen::Vector3d, kMaxReducedBodies> first_moment_kgm{};
  std::array<Eigen::Matrix3d, kMaxReducedBodies> inertia_O_kgm2{};
  // Newton-Euler at some qdd (computeReducedInverseDynamics).
  std::array<SpatialVector, kMaxReducedBodies> A{};      ///< body accelerations
  std::array<SpatialVector, kMaxReducedBodies> IV{};     ///< body momenta I V
  std::array<SpatialVector, kMaxReducedBodies> IA{};     ///< I A
  std::array<SpatialVector, kMaxReducedBodies> F{};      ///< body inertial forces I A + V x* I V
  std::array<SpatialVector, kMaxReducedBodies> F_tot{};  ///< subtree force through each joint
};

/// Forward kinematics, world inertias and body velocities at (q, qd) (size n each). @rt
void computeReducedKinematics(const ReducedArmModel& model, ReducedArmData& data, const ReducedVector& q,
                              const ReducedVector& qd) noexcept;

/// Inverse dynamics tau = M(q) qdd + C(q, qd) qd + g(q) at the kinematics of the last
/// computeReducedKinematics (Newton-Euler, R1-R4). @rt
void computeReducedInverseDynamics(const ReducedArmModel& model, ReducedArmData& data, const ReducedVector& qdd,
                                   ReducedVector& tau) noexcept;

/// Joint-space inertia M(q) (n x n) at the last kinematics, by composite rigid bodies:
/// M_ij = s_i . (I^C_j s_j) for i an ancestor of (or equal to) j (R5). @rt
void computeReducedMassMatrix(const ReducedArmModel& model, const ReducedArmData& data, ReducedMatrix& mass) noexcept;

/// Analytic partial derivatives of the inverse dynamics ID(q, qd, qdd) with respect to q and
/// qd (n x n each) at the last kinematics and `qdd` (R6-R8 collected into composite subtree
/// quantities, R13: O(n) 6 x 6 work and one dot product per entry). Runs the Newton-Euler pass
/// at qdd itself (tau is left in `tau`). @rt
void computeReducedInverseDynamicsDerivatives(const ReducedArmModel& model, ReducedArmData& data,
                                              const ReducedVector& qdd, ReducedVector& tau, ReducedMatrix& dtau_dq,
                                              ReducedMatrix& dtau_dqd) noexcept;

/// The same derivatives body by body (R6-R8: for each joint, every body it moves; O(n^2) spatial
/// operations): the first implementation, kept as an independent check of the composite form. @rt
void computeReducedInverseDynamicsDerivativesPerBody(const ReducedArmModel& model, ReducedArmData& data,
                                                     const ReducedVector& qdd, ReducedVector& tau,
                                                     ReducedMatrix& dtau_dq, ReducedMatrix& dtau_dqd) noexcept;

/// World position of a body point after computeReducedKinematics.
[[nodiscard]] inline Eigen::Vector3d reducedPointInWorld(const ReducedArmData& data, int body,
                                                         const Eigen::Vector3d& p_B) noexcept {
  return data.o_W[static_cast<std::size_t>(body)] + data.R_WB[static_cast<std::size_t>(body)] * p_B;
}

}  // namespace fullarm::plant
