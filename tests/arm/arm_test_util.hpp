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

/// Path of a file in the source tree.
std::string sourcePath(const std::string& relative);

}  // namespace fullarm::arm::test
