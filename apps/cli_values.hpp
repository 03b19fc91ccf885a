#pragma once
// Parsing of command-line values that CLI11 validators do not cover.

#include <Eigen/Core>
#include <string>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::app {

/// Parses a joint vector such as "0, -0.3, 0, 1.57, 0, 0, 0" (commas and/or spaces) for the
/// option `option`. Fewer values than joints fill the rest from the default posture; each
/// value must be finite and inside its joint's range.
/// @throws arm::ConfigError with key path `option` and the offending element.
Eigen::VectorXd parseJointVector(std::string_view text, const arm::ArmModel& model, const std::string& option);

}  // namespace fullarm::app
