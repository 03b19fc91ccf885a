#include "fullarm/controllers/arm_controller.hpp"

#include <limits>
#include <string>

#include "fullarm/arm/dynamics.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::controllers {

ArmControllerModel makeArmControllerModel(const GainsConfig& gains, const arm::ArmModel& model) {
  if (gains.joints.size() > static_cast<std::size_t>(kMaxControlledJoints)) {
    throw core::ConfigError(gains.source, "joints",
                            "expected at most " + std::to_string(kMaxControlledJoints) + " joints, got " +
                                std::to_string(gains.joints.size()));
  }
  ArmControllerModel c;
  c.num_joints = static_cast<int>(gains.joints.size());
  for (std::size_t i = 0; i < gains.joints.size(); ++i) {
    const JointGains& g = gains.joints[i];
    const int index = model.jointIndex(g.name);
    if (index < 0 || model.joints[static_cast<std::size_t>(index)].is_hand) {
      throw core::ConfigError(gains.source, "joints[" + std::to_string(i) + "].name",
                              "'" + g.name + "' is not an arm joint of model " + model.name);
    }
    c.model_index[i] = index;
    c.joints[i] = makeJointControllerModel(g, gains.controller, gains.control_period_s);
  }
  return c;
}

void resetArmController(const ArmControllerModel& controller, ArmControllerData& data,
                        const Eigen::Ref<const Eigen::VectorXd>& q) noexcept {
  data.faults = kFaultNone;
  for (int i = 0; i < controller.num_joints; ++i) {
    const auto k = static_cast<std::size_t>(i);
    resetJointController(controller.joints[k], data.joints[k], q[controller.model_index[k]]);
    data.faults |= data.joints[k].faults;
  }
}

void stepArmController(const arm::ArmModel& model, arm::ArmData& arm_data, const ArmControllerModel& controller,
                       ArmControllerData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_load_cell_nm,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_env_nm,
                       Eigen::Ref<Eigen::VectorXd> valve_command_v) noexcept {
  // Gravity needs a finite configuration; a non-finite one is caught per joint below.
  const bool q_finite = q.allFinite();
  if (q_finite) arm::computeGravityTorques(model, arm_data, q);
  std::uint32_t faults = kFaultNone;
  for (int i = 0; i < controller.num_joints; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const int m = controller.model_index[k];
    JointInput in;
    in.q_rad = q[m];
    in.tau_load_cell_nm = tau_load_cell_nm[i];
    in.tau_env_nm = tau_env_nm[i];
    // Eq. (4)'s tau_ge from fullarm::arm (NaN when the configuration is not finite).
    in.tau_gravity_nm = q_finite ? arm_data.tau_gravity[m] : std::numeric_limits<double>::quiet_NaN();
    valve_command_v[i] = stepJointController(controller.joints[k], data.joints[k], in);
    faults |= data.joints[k].faults;
  }
  data.faults = faults;
  // One faulted joint stops the arm: every valve to null.
  if (faults != kFaultNone) {
    for (int i = 0; i < controller.num_joints; ++i) valve_command_v[i] = 0.0;
  }
}

}  // namespace fullarm::controllers
