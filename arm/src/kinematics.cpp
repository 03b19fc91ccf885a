#include "fullarm/arm/kinematics.hpp"

#include <cassert>

namespace fullarm::arm {

// K1: modified DH link transforms (reports/equations.md).
void computeForwardKinematics(const ArmModel& model, ArmData& data,
                              const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  const int n = model.numJoints();
  assert(q.size() == n);
  data.q = q;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Joint& joint = model.joints[k];
    const Eigen::Isometry3d& X_WP = joint.parent < 0 ? model.X_WB : data.X_WL[static_cast<std::size_t>(joint.parent)];
    // X_WL = X_WP * X_PL0 * Rz(q): the link frame turns about its own +z.
    Eigen::Isometry3d X_WL0 = X_WP * joint.X_PL0;
    data.X_WL[k] = X_WL0 * Eigen::AngleAxisd(q[i], Eigen::Vector3d::UnitZ());
    data.z_W[k] = data.X_WL[k].linear().col(2);
    data.o_W[k] = data.X_WL[k].translation();
    data.com_W[k] = data.X_WL[k] * joint.inertial.com_m;
  }
  data.X_WT = data.X_WL[static_cast<std::size_t>(model.tool_link)] * model.X_LT;
  ++data.forward_kinematics_passes;
}

// K3: geometric point Jacobian (reports/equations.md).
void computePointJacobian(const ArmModel& model, const ArmData& data, int link, const Eigen::Vector3d& p_W,
                          PointJacobian& J) noexcept {
  const int n = model.numJoints();
  assert(link >= 0 && link < n);
  J.resize(6, n);  // within the fixed capacity: no allocation
  J.setZero();
  // Revolute joint j contributes z_j x (p - o_j) to the linear and z_j to the angular velocity.
  for (int j = link; j >= 0; j = model.joints[static_cast<std::size_t>(j)].parent) {
    const auto k = static_cast<std::size_t>(j);
    J.block<3, 1>(0, j) = data.z_W[k].cross(p_W - data.o_W[k]);
    J.block<3, 1>(3, j) = data.z_W[k];
  }
}

}  // namespace fullarm::arm
