#pragma once
// The arm model summary shown by `fullarm arm show` and the first step of `fullarm demo`.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <ostream>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// What `arm show` reports about a model at one posture.
struct ArmSummary {
  Eigen::VectorXd q;           ///< posture the pose and torques refer to [rad]
  Eigen::Isometry3d X_WT;      ///< hand point pose at q
  Eigen::Vector3d shoulder_W;  ///< origin of the first joint (shoulder centre) [m]
  double upper_arm_m = 0.0;
  double forearm_m = 0.0;
  double hand_m = 0.0;
  double total_mass_kg = 0.0;
  double reach_m = 0.0;  ///< largest sampled shoulder-to-hand distance
  int reach_samples = 0;
  Eigen::VectorXd tau_gravity;                  ///< gravity torques at q [N m]
  bool holds_itself = true;                     ///< every |gravity torque| within the torque limit
  std::vector<Eigen::Vector3d> hand_samples_W;  ///< hand points of the reach samples
};

/// Computes the summary; reach by sampling `samples` uniform configurations (fixed seed).
ArmSummary summarizeArm(const arm::ArmModel& model, const Eigen::VectorXd& q, int samples);

/// Human-readable summary on `out`.
void printArmSummary(const arm::ArmModel& model, const ArmSummary& summary, std::ostream& out);

/// Adds the arm sections (joint table, link lengths, reach cross-section, gravity) and the
/// `results.arm` keys to a report.
void addArmToReport(const arm::ArmModel& model, const ArmSummary& summary, reports::Report& report);

}  // namespace fullarm::app
