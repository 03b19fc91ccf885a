#pragma once
/// @file
/// Rigid-body dynamics of the arm tree: M(q) qdd + C(q, qd) qd + g(q) = tau.
/// Every function here runs the one rigid-body algorithm of the arm, the spatial Newton-Euler
/// and composite rigid bodies of rigid_body_dynamics.hpp, on the unreduced arm (every joint a
/// body, ArmData::tree), from the frames of computeForwardKinematics. No allocation.

#include <Eigen/Core>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Gravity torques g(q) = dV/dq (the torque that holds the arm still) at the kinematics already
/// in `data` (the last computeForwardKinematics, at data.q), into data.tau_gravity; counts one
/// data.gravity_passes. The 1 kHz tick computes the kinematics once and calls this.
/// @rt
void computeGravityTorquesAtKinematics(const ArmModel& model, ArmData& data) noexcept;

/// Convenience: computeForwardKinematics at q, then computeGravityTorquesAtKinematics.
/// @rt
void computeGravityTorques(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// Inverse dynamics tau = M qdd + C qd + g, into data.tau. All vectors size n.
/// @rt
void computeInverseDynamics(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd,
                            const Eigen::Ref<const Eigen::VectorXd>& qdd) noexcept;

/// Coriolis and centrifugal torques C(q, qd) qd, into data.tau_coriolis.
/// @rt
void computeCoriolisTorques(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                            const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept;

/// Joint-space mass matrix M(q), into data.mass_matrix (symmetric positive definite for a
/// physically valid model), by composite rigid bodies (R5).
/// @rt
void computeMassMatrix(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// Potential energy V(q) = -sum m_k g . c_k [J] (zero at the world origin height).
/// @rt
[[nodiscard]] double computePotentialEnergy(const ArmModel& model, ArmData& data,
                                            const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// Kinetic energy 0.5 qd^T M(q) qd = 0.5 sum_b V_b . (I_b V_b) [J] (body velocities and spatial
/// inertias of the spatial algorithm).
/// @rt
[[nodiscard]] double computeKineticEnergy(const ArmModel& model, ArmData& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& q,
                                          const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept;

/// The load on one joint turning with the rest of the arm locked at a posture: a rigid body
/// about a fixed axis, so its inertia M_ii does not depend on q_i and its gravity torque is
/// g_i(q_i) = gravity_cos_nm cos q_i + gravity_sin_nm sin q_i exactly (the single-axis model of
/// the plant's one-joint mode and of the offline controller design).
struct SingleAxisLoad {
  double inertia_kgm2 = 0.0;    ///< M_ii at the posture [kg m^2]
  double gravity_cos_nm = 0.0;  ///< g_i at q_i = 0 [N m]
  double gravity_sin_nm = 0.0;  ///< g_i at q_i = pi/2 [N m]
};

/// The single-axis load of `joint` with every other joint at `posture` (size model.numJoints();
/// its entry for `joint` only sets where M_ii is evaluated). Allocates (configuration time).
/// @throws std::invalid_argument for a bad joint index or posture size.
[[nodiscard]] SingleAxisLoad computeSingleAxisLoad(const ArmModel& model, int joint, const Eigen::VectorXd& posture);

}  // namespace fullarm::arm
