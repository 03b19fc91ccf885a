#include "arm_test_util.hpp"

#include <cstdlib>
#include <stdexcept>

#include <kdl/treeidsolver_recursive_newton_euler.hpp>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kdl_conversion.hpp"

namespace fullarm::arm::test {

std::string sourcePath(const std::string& relative) {
  const char* root = std::getenv("FULLARM_SOURCE_DIR");
  return std::string(root != nullptr ? root : FULLARM_TEST_SOURCE_DIR) + "/" + relative;
}

const ArmModel& defaultModel() {
  static const ArmModel model = loadArmModel(sourcePath("config/dts_master.yaml"));
  return model;
}

const ArmModel& armOnlyModel() {
  static const ArmModel model = [] {
    ArmModel m = defaultModel();
    m.joints.resize(static_cast<std::size_t>(m.numArmJoints()));
    validateArmModel(m);
    return m;
  }();
  return model;
}

Eigen::VectorXd randomConfiguration(const ArmModel& model, std::mt19937& rng) {
  Eigen::VectorXd q(model.numJoints());
  for (int i = 0; i < model.numJoints(); ++i) {
    const JointLimits& lim = model.joints[static_cast<std::size_t>(i)].limits;
    std::uniform_real_distribution<double> u(lim.min_rad, lim.max_rad);
    q[i] = u(rng);
  }
  return q;
}

Eigen::VectorXd randomVector(int n, double scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

Eigen::VectorXi kdlJointIndices(const ArmModel& model, const KDL::Tree& tree) {
  Eigen::VectorXi index(model.numJoints());
  for (int i = 0; i < model.numJoints(); ++i) {
    const auto it = tree.getSegments().find(model.joints[static_cast<std::size_t>(i)].name);
    if (it == tree.getSegments().end()) throw std::runtime_error("joint missing from the KDL tree");
    index[i] = static_cast<int>(GetTreeElementQNr(it->second));
  }
  return index;
}

KdlJointAtRest kdlJointAtRest(const ArmModel& model, const Eigen::VectorXd& q, int joint) {
  const KDL::Tree tree = toKdlTree(model);
  const Eigen::VectorXi index = kdlJointIndices(model, tree);
  const unsigned n = tree.getNrOfJoints();
  KDL::JntArray q_kdl(n);
  for (int i = 0; i < q.size(); ++i) q_kdl(static_cast<unsigned>(index[i])) = q[i];
  const KDL::JntArray zero(n);
  KDL::JntArray unit(n);
  unit(static_cast<unsigned>(index[joint])) = 1.0;
  const KDL::WrenchMap no_wrenches;
  KDL::JntArray tau(n);
  const KDL::Vector g(model.gravity_W_mps2.x(), model.gravity_W_mps2.y(), model.gravity_W_mps2.z());
  KDL::TreeIdSolver_RNE with_gravity(tree, g);
  if (with_gravity.CartToJnt(q_kdl, zero, zero, no_wrenches, tau) < 0) throw std::runtime_error("KDL gravity failed");
  KdlJointAtRest r;
  r.gravity_nm = tau(static_cast<unsigned>(index[joint]));
  KDL::TreeIdSolver_RNE without_gravity(tree, KDL::Vector::Zero());
  if (without_gravity.CartToJnt(q_kdl, zero, unit, no_wrenches, tau) < 0)
    throw std::runtime_error("KDL inertia failed");
  r.inertia_kgm2 = tau(static_cast<unsigned>(index[joint]));
  return r;
}

}  // namespace fullarm::arm::test
