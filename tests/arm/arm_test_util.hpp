#pragma once
// Shared fixtures of the arm tests: the default model, seeded random configurations and
// KDL oracles.

#include <Eigen/Core>
#include <kdl/tree.hpp>
#include <random>
#include <string>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm::test {

/// The default DTS master model from config/dts_master.yaml (loaded once).
const ArmModel& defaultModel();

/// The default model without its hand joints (a pure 7-DOF chain).
const ArmModel& armOnlyModel();

/// Uniform random configuration within the joint limits.
Eigen::VectorXd randomConfiguration(const ArmModel& model, std::mt19937& rng);

/// Uniform random vector in [-scale, scale]^n.
Eigen::VectorXd randomVector(int n, double scale, std::mt19937& rng);

/// KDL joint index of each fullarm joint (KDL numbers tree joints by insertion order).
Eigen::VectorXi kdlJointIndices(const ArmModel& model, const KDL::Tree& tree);

/// KDL's answer for one joint at rest at posture `q` (TreeIdSolver_RNE, the model's gravity):
/// the gravity torque the joint holds and the joint's own inertia (the mass matrix's diagonal
/// entry: the torque for a unit acceleration of that joint alone, without gravity).
struct KdlJointAtRest {
  double gravity_nm = 0.0;
  double inertia_kgm2 = 0.0;
};
[[nodiscard]] KdlJointAtRest kdlJointAtRest(const ArmModel& model, const Eigen::VectorXd& q, int joint);

/// Path of a file in the source tree.
std::string sourcePath(const std::string& relative);

}  // namespace fullarm::arm::test
