#pragma once
// A second rigid-body dynamics of the arm, used only as a test oracle beside KDL: recursive
// Newton-Euler in the world frame (Craig, Introduction to Robotics, 3rd ed., section 6.5,
// outward/inward iterations, generalised to the hand tree), the mass matrix column by column from
// it, and gravity as the gradient of the potential energy over each joint's subtree. Independent
// of the spatial algorithm of fullarm::arm (rigid_body_dynamics.hpp) that the library uses.
// Allocates; not for the real-time path.

#include <Eigen/Core>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm::test {

/// tau = M(q) qdd + C(q, qd) qd + g(q) [N m], model order.
[[nodiscard]] Eigen::VectorXd worldFrameInverseDynamics(const ArmModel& model, const Eigen::VectorXd& q,
                                                        const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd);
/// C(q, qd) qd [N m].
[[nodiscard]] Eigen::VectorXd worldFrameCoriolisTorques(const ArmModel& model, const Eigen::VectorXd& q,
                                                        const Eigen::VectorXd& qd);
/// M(q) [kg m^2], column j the Newton-Euler torque of qdd = e_j at rest without gravity.
[[nodiscard]] Eigen::MatrixXd worldFrameMassMatrix(const ArmModel& model, const Eigen::VectorXd& q);
/// g(q) = dV/dq = -z_i . sum_k (c_k - o_i) x m_k g over the links joint i moves [N m].
[[nodiscard]] Eigen::VectorXd worldFrameGravityTorques(const ArmModel& model, const Eigen::VectorXd& q);

}  // namespace fullarm::arm::test
