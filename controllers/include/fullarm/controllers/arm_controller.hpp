#pragma once
/// @file
/// The joint controllers of joint_controller.hpp for every controlled joint of the arm, with
/// the expected gravity torques (tau_ge of Eq. 4) from fullarm::arm's Newton-Euler gravity.

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/controllers/joint_controller.hpp"

namespace fullarm::controllers {

/// Largest number of controlled joints.
inline constexpr int kMaxControlledJoints = arm::kMaxJoints;

/// Fixed-capacity per-controlled-joint vector (no heap).
using ControlVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxControlledJoints, 1>;

/// One JointControllerModel per joint of a gains file, and where each joint sits in the arm.
struct ArmControllerModel {
  int num_joints = 0;
  std::array<JointControllerModel, kMaxControlledJoints> joints{};
  std::array<int, kMaxControlledJoints> model_index{};  ///< index in ArmModel::joints
};

/// Builds the models of every joint of `gains` (in the file's order) for `model`.
/// @throws core::ConfigError for an unknown joint or invalid gains.
[[nodiscard]] ArmControllerModel makeArmControllerModel(const GainsConfig& gains, const arm::ArmModel& model);

/// State of every joint.
struct ArmControllerData {
  std::array<JointControllerData, kMaxControlledJoints> joints{};
  std::uint32_t faults = kFaultNotConfigured;  ///< OR of the joints' fault bits
};

/// Resets every joint at rest at `q` (full model configuration, size model.numJoints()). @rt
void resetArmController(const ArmControllerModel& controller, ArmControllerData& data,
                        const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// One control period for every controlled joint: gravity g(q) from fullarm::arm (into
/// arm_data.tau_gravity), then stepJointController per joint.
/// @param q                full configuration [rad], size model.numJoints() (hand joints included)
/// @param tau_load_cell_nm load-cell readings, size controller.num_joints (controller order)
/// @param tau_env_nm       environment torques on the links, size controller.num_joints
/// @param valve_command_v  output [V], size controller.num_joints; all zero if any joint faults
/// @rt
void stepArmController(const arm::ArmModel& model, arm::ArmData& arm_data, const ArmControllerModel& controller,
                       ArmControllerData& data, const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_load_cell_nm,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_env_nm,
                       Eigen::Ref<Eigen::VectorXd> valve_command_v) noexcept;

}  // namespace fullarm::controllers
