#pragma once
/// @file
/// The human arm's strength and weight on the arm model's kinematics (config/human_arm.yaml):
/// per joint, direction-dependent maximal isometric torques tau_min(q) <= tau <= tau_max(q)
/// with posture factors, a strength scale, and the person's segment masses and centres of mass,
/// from which g_human(q) is computed. The arm model supplies only the kinematics (its own link
/// masses are not used here).
///
/// Sign convention: a joint torque is the torque the person's muscles apply at that joint,
/// positive toward +q of the arm model. tau_max (>= 0) is the strength of the action that turns
/// the joint toward +q, tau_min (<= 0) minus the strength of the opposite action.

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"

namespace fullarm::accessibility {

/// A piecewise-linear strength factor of one joint's angle (held constant beyond the ends).
struct PostureFactor {
  int joint = -1;                 ///< arm-model joint whose angle it reads
  std::vector<double> angle_rad;  ///< strictly increasing breakpoints [rad]
  std::vector<double> factor;     ///< factor at each breakpoint (> 0)
};

/// The maximal isometric torque of one joint action.
struct JointAction {
  std::string action;                  ///< anatomical name ("elbow flexion")
  double torque_nm = 0.0;              ///< maximal isometric torque in the reference posture [N m] (> 0)
  std::vector<PostureFactor> posture;  ///< multiplied together
};

/// The two actions of one joint.
struct JointStrength {
  int joint = -1;        ///< arm-model joint index
  JointAction positive;  ///< turns the joint toward +q
  JointAction negative;  ///< turns the joint toward -q
};

/// Which stretch of the arm model a body segment lies along.
enum class SegmentSpan {
  kUpperArm,  ///< the link of model.upper_arm_joint, from z = -d to its origin (d its DH offset)
  kForearm,   ///< the link of model.forearm_joint, likewise
  kHand,      ///< the tool link, from its origin to the hand point
};

/// One body segment of the person.
struct HumanSegment {
  std::string name;
  SegmentSpan span = SegmentSpan::kUpperArm;
  double mass_fraction = 0.0;  ///< of the body mass
  double com_fraction = 0.0;   ///< centre of mass from the proximal end, fraction of the span
};

/// The person's arm: strength and weight. Load with loadHumanArm().
struct HumanArm {
  std::filesystem::path source;  ///< file it was read from (empty if built in code)
  double body_mass_kg = 0.0;
  double strength_scale = 1.0;        ///< multiplies every torque limit (a population draw)
  std::vector<JointStrength> joints;  ///< the joints the person drives, in arm-model order
  std::vector<HumanSegment> segments;

  /// Arm-model indices of `joints`, in order (the columns of the force program).
  [[nodiscard]] std::vector<int> jointIndices() const;
};

/// Reads and validates a human arm file against the arm model (joint names must exist in it,
/// each at most once; the model must name its upper-arm and forearm joints when a segment uses
/// them). Strict: unknown keys are errors.
/// @throws core::ConfigError naming the file, key path, value and what was expected
[[nodiscard]] HumanArm loadHumanArm(const std::filesystem::path& file, const arm::ArmModel& model);
/// Same from text; `file` names the source in errors.
[[nodiscard]] HumanArm parseHumanArm(std::string_view yaml_text, const std::filesystem::path& file,
                                     const arm::ArmModel& model);
/// core::defaultConfigPath("human_arm.yaml").
[[nodiscard]] std::filesystem::path defaultHumanArmPath();

/// The factor of `action` at configuration `q` (product of its posture factors).
[[nodiscard]] double postureFactor(const JointAction& action, const Eigen::VectorXd& q);

/// tau_min(q) and tau_max(q) per entry of human.joints [N m], strength_scale applied.
void computeTorqueLimits(const HumanArm& human, const Eigen::VectorXd& q, Eigen::VectorXd& tau_min_nm,
                         Eigen::VectorXd& tau_max_nm);

/// Centre of mass of `segment` in its link's frame, on `model`'s kinematics [m]; `link` is set
/// to that link.
[[nodiscard]] Eigen::Vector3d segmentCom(const arm::ArmModel& model, const HumanSegment& segment, int& link);

/// g_human(q) = dV_human/dq: the torque that holds the person's arm segments against gravity
/// (model.gravity_W_mps2) at the kinematics of `fk` (computeForwardKinematics already run), a
/// configuration vector of size model.numJoints() [N m]. Same sign as arm::ArmData::tau_gravity.
[[nodiscard]] Eigen::VectorXd computeHumanGravityTorques(const arm::ArmModel& model, const HumanArm& human,
                                                         const arm::ArmData& fk);

}  // namespace fullarm::accessibility
