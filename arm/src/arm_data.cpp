#include "fullarm/arm/arm_data.hpp"

#include <stdexcept>
#include <string>

namespace fullarm::arm {

ArmData::ArmData(const ArmModel& model) {
  if (model.numJoints() > kMaxBodies) {
    throw std::invalid_argument("ArmData: model " + model.name + " has " + std::to_string(model.numJoints()) +
                                " joints, at most " + std::to_string(kMaxBodies) + " are supported");
  }
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
  body_vector = BodyVector::Zero(ni);
  body_matrix = BodyMatrix::Zero(ni, ni);
  // The tree of the unreduced arm: every joint a body, model order (parents precede children).
  tree.n = static_cast<int>(n);
  for (int i = 0; i < tree.n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    tree.parent[k] = model.joints[k].parent;
    tree.order[k] = i;
    for (int b = 0; b < tree.n; ++b) tree.supports[k][static_cast<std::size_t>(b)] = jointMovesLink(model, i, b);
  }
}

}  // namespace fullarm::arm
