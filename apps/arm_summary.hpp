#pragma once
// The arm model summary shown by `fullarm arm show` and the first step of `fullarm demo`.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ostream>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/reach.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// What `arm show` reports about a model at one posture.
struct ArmSummary {
  Eigen::VectorXd q;       ///< posture the pose and torques refer to [rad]
  Eigen::Isometry3d X_WT;  ///< hand point pose at q
  double upper_arm_m = 0.0;
  double forearm_m = 0.0;
  double hand_m = 0.0;
  double total_mass_kg = 0.0;
  Eigen::VectorXd tau_gravity;  ///< gravity torques at q [N m]
  bool holds_itself = true;     ///< every |gravity torque| within the torque limit
  arm::ReachSample reach;       ///< hand points of the reach postures, shoulder centre, reach
};

/// Computes the summary; reach by arm::sampleReach over `samples` postures (fixed seed).
ArmSummary summarizeArm(const arm::ArmModel& model, const Eigen::VectorXd& q, int samples);

/// Human-readable summary on `out`.
void printArmSummary(const arm::ArmModel& model, const ArmSummary& summary, std::ostream& out);

/// Adds the arm sections (joint table, link lengths, reach cross-section, gravity) and the
/// `results.arm` keys to a report.
void addArmToReport(const arm::ArmModel& model, const ArmSummary& summary, reports::Report& report);

}  // namespace fullarm::app
