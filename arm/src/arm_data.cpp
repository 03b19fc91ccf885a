#include "fullarm/arm/arm_data.hpp"

namespace fullarm::arm {

ArmData::ArmData(const ArmModel& model) {
  const auto n = static_cast<std::size_t>(model.numJoints());
  const auto ni = static_cast<Eigen::Index>(n);
  q = Eigen::VectorXd::Zero(ni);
  X_WL.assign(n, Eigen::Isometry3d::Identity());
  z_W.assign(n, Eigen::Vector3d::UnitZ());
  o_W.assign(n, Eigen::Vector3d::Zero());
  com_W.assign(n, Eigen::Vector3d::Zero());
  tau_gravity = Eigen::VectorXd::Zero(ni);
  tau = Eigen::VectorXd::Zero(ni);
  tau_coriolis = Eigen::VectorXd::Zero(ni);
  mass_matrix = Eigen::MatrixXd::Zero(ni, ni);
  qdd_unit = Eigen::VectorXd::Zero(ni);
  omega.assign(n, Eigen::Vector3d::Zero());
  omega_dot.assign(n, Eigen::Vector3d::Zero());
  accel_origin.assign(n, Eigen::Vector3d::Zero());
  force.assign(n, Eigen::Vector3d::Zero());
  moment.assign(n, Eigen::Vector3d::Zero());
  mass_moment.assign(n, Eigen::Vector3d::Zero());
  subtree_mass_kg.assign(n, 0.0);
  inertia_W.assign(n, Eigen::Matrix3d::Zero());
}

}  // namespace fullarm::arm
