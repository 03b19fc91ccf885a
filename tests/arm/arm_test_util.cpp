#include "arm_test_util.hpp"

#include <cstdlib>
#include <stdexcept>

#include "fullarm/arm/arm_yaml.hpp"

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

}  // namespace fullarm::arm::test
