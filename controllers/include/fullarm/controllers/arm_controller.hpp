#pragma once
/// @file
/// The joint controllers of joint_controller.hpp for every controlled joint of the arm.
///
/// ## What crosses the boundary
/// The controlled joints are the gains file's joints, in its order: an arm::JointSelection
/// (arm/joint_selection.hpp). stepArmController takes what the arm and haptics layers compute
/// over the whole configuration as configuration vectors in arm-model order (hand joints
/// included): the joint angles q, the gravity torques g(q) (tau_ge of Eq. 4, computed once per
/// tick by the caller) and the contact torques (fullarm::haptics' ContactData::tau_contact_nm). What exists only per controlled joint is a
/// subset vector in the controller's order: the load-cell readings in, the valve commands out.
/// The controller reads its joints' entries of the configuration vectors through its selection.

#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/joint_selection.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/controllers/joint_controller.hpp"

namespace fullarm::controllers {

/// Largest number of controlled joints.
inline constexpr int kMaxControlledJoints = arm::kMaxJoints;

/// Fixed-capacity per-controlled-joint vector (no heap).
using ControlVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxControlledJoints, 1>;

/// One JointControllerModel per joint of a gains file, and where each joint sits in the arm.
struct ArmControllerModel {
  /// The controlled joints: subset position k (the gains file's k-th joint) <-> model joint.
  arm::JointSelection selection;
  std::array<JointControllerModel, kMaxControlledJoints> joints{};  ///< in the selection's order
  /// Number of controlled joints (length of the subset vectors). @rt
  [[nodiscard]] int numJoints() const noexcept { return selection.size(); }
};

/// Builds the models of every joint of `gains` (in the file's order) for `model`.
/// @throws core::ConfigError for an unknown joint or invalid gains.
[[nodiscard]] ArmControllerModel makeArmControllerModel(const GainsConfig& gains, const arm::ArmModel& model);

/// State of every joint.
struct ArmControllerData {
  std::array<JointControllerData, kMaxControlledJoints> joints{};
  /// The arm's status: the first joint's fault (in the selection's order) and the OR of every
  /// joint's fault bits.
  core::RtStatus status =
      core::RtStatus::fault(core::RtCode::kNotConfigured, kFaultNotConfigured, "controller not reset");
};

/// Resets every joint at rest at `q` (full model configuration, size model.numJoints()). @rt
void resetArmController(const ArmControllerModel& controller, ArmControllerData& data,
                        const Eigen::Ref<const Eigen::VectorXd>& q) noexcept;

/// One control period for every controlled joint: stepJointController per joint, with its
/// entries of the configuration vectors (boundary rule in the file comment).
/// @param q                configuration [rad], model order, size model.numJoints()
/// @param tau_gravity_nm   g(q) at q [N m], model order (arm::computeGravityTorquesAtKinematics)
/// @param tau_contact_nm   contact torques (the environment's torques on the links) [N m], model order
/// @param tau_load_cell_nm load-cell readings [N m], controller order, size controller.numJoints()
/// @param valve_command_v  output [V], controller order, size controller.numJoints(); all zero if
///                         any joint faults
/// @rt
void stepArmController(const ArmControllerModel& controller, ArmControllerData& data,
                       const Eigen::Ref<const Eigen::VectorXd>& q,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_gravity_nm,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_contact_nm,
                       const Eigen::Ref<const Eigen::VectorXd>& tau_load_cell_nm,
                       Eigen::Ref<Eigen::VectorXd> valve_command_v) noexcept;

}  // namespace fullarm::controllers
