#pragma once
// Parsing of command-line values that CLI11 validators do not cover.

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::app {

/// Parses a joint vector such as "0, -0.3, 0, 1.57, 0, 0, 0" (commas and/or spaces) for the
/// option `option`. Fewer values than joints fill the rest from the default posture; each
/// value must be finite and inside its joint's range.
/// @throws core::ConfigError with key path `option` and the offending element.
Eigen::VectorXd parseJointVector(std::string_view text, const arm::ArmModel& model, const std::string& option);

/// The file named by a configuration option (`option_value`), or `default_path()` (e.g.
/// arm::defaultArmModelPath) when the option was not given (empty).
std::filesystem::path configPathOr(const std::string& option_value, std::filesystem::path (*default_path)());

/// A joint's model name without its "R_" side prefix ("R_EB" -> "EB"), as reports and
/// command-line options name joints.
std::string shortJointName(const std::string& name);

}  // namespace fullarm::app
