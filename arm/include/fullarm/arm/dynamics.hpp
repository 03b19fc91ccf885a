#pragma once
/// @file
/// Rigid-body dynamics of the arm tree: M(q) qdd + C(q, qd) qd + g(q) = tau.
/// Recursive Newton-Euler in the world frame (Craig, Introduction to Robotics, 3rd ed.,
/// section 6.5, outward/inward iterations), generalised to the hand tree. No allocation.

#include <Eigen/Core>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Gravity torques g(q) = dV/dq (the torque that holds the arm still), into data.tau_gravity.
/// Also runs computeForwardKinematics.
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
/// physically valid model). Built column by column from Newton-Euler (O(n^2)).
/// @rt
void computeMassMatrix(const ArmModel& model, ArmData& data, const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// Potential energy V(q) = -sum m_k g . c_k [J] (zero at the world origin height).
/// @rt
[[nodiscard]] double computePotentialEnergy(const ArmModel& model, ArmData& data,
                                            const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// Kinetic energy 0.5 qd^T M(q) qd [J]. Runs computeMassMatrix.
/// @rt
[[nodiscard]] double computeKineticEnergy(const ArmModel& model, ArmData& data,
                                          const Eigen::Ref<const Eigen::VectorXd>& q,
                                          const Eigen::Ref<const Eigen::VectorXd>& qd) noexcept;

}  // namespace fullarm::arm
