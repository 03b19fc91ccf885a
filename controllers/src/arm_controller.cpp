#include "fullarm/controllers/arm_controller.hpp"

#include <algorithm>
#include <string>
#include <vector>

#include "fullarm/core/config_error.hpp"

namespace fullarm::controllers {

ArmControllerModel makeArmControllerModel(const GainsConfig& gains, const arm::ArmModel& model) {
  if (gains.joints.size() > static_cast<std::size_t>(kMaxControlledJoints)) {
    throw core::ConfigError(gains.source, "joints",
                            "expected at most " + std::to_string(kMaxControlledJoints) + " joints, got " +
                                std::to_string(gains.joints.size()));
  }
  ArmControllerModel c;
  std::vector<int> indices;
  for (std::size_t i = 0; i < gains.joints.size(); ++i) {
    const JointGains& g = gains.joints[i];
    const int index = model.jointIndex(g.name);
    if (index < 0 || model.joints[static_cast<std::size_t>(index)].is_hand) {
      throw core::ConfigError(gains.source, "joints[" + std::to_string(i) + "].name",
                              "'" + g.name + "' is not an arm joint of model " + model.name);
    }
    if (std::find(indices.begin(), indices.end(), index) != indices.end()) {
      throw core::ConfigError(gains.source, "joints[" + std::to_string(i) + "].name",
                              "'" + g.name + "' is listed twice");
    }
    indices.push_back(index);
    c.joints[i] = makeJointControllerModel(g, gains.controller, gains.control_period_s);
  }
  c.selection = arm::JointSelection(model.numJoints(), indices);
  return c;
}

void resetArmController(const ArmControllerModel& controller, ArmControllerData& data,
                        const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  data.status.clear();
  for (int i = 0; i < controller.numJoints(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    resetJointController(controller.joints[k], data.joints[k], q[controller.selection.modelIndex(i)]);
    const core::RtStatus& s = data.joints[k].status;
    if (!s.ok()) data.status.raise(s.code, s.faults, s.message);
  }
}

void stepArmController(const ArmControllerModel& controller, ArmControllerData& data,
                       const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_gravity_nm,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_contact_nm,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_load_cell_nm,
                       Eigen::Ref<Eigen::VectorXd> valve_command_v) noexcept {
  core::RtStatus status;
  for (int i = 0; i < controller.numJoints(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const int m = controller.selection.modelIndex(i);
    JointInput in;
    in.q_rad = q[m];
    in.tau_load_cell_nm = tau_load_cell_nm[i];
    in.tau_contact_nm = tau_contact_nm[m];
    in.tau_gravity_nm = tau_gravity_nm[m];  // Eq. (4)'s tau_ge, computed once by the caller
    valve_command_v[i] = stepJointController(controller.joints[k], data.joints[k], in);
    const core::RtStatus& s = data.joints[k].status;
    if (!s.ok()) status.raise(s.code, s.faults, s.message);
  }
  data.status = status;
  // One faulted joint stops the arm: every valve to null.
  if (!status.ok()) {
    for (int i = 0; i < controller.numJoints(); ++i) valve_command_v[i] = 0.0;
  }
}

}  // namespace fullarm::controllers
