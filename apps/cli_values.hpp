#pragma once
// Parsing of command-line values that CLI11 validators do not cover.

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>

#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/controllers/gains.hpp"

namespace fullarm::app {

/// Parses a joint vector such as "0, -0.3, 0, 1.57, 0, 0, 0" (commas and/or spaces) for the
/// option `option`. Fewer values than joints fill the rest from the default posture; each
/// value must be finite and inside its joint's range.
/// @throws core::ConfigError with key path `option` and the offending element.
Eigen::VectorXd parseJointVector(std::string_view text, const arm::ArmModel& model, const std::string& option);

/// The file named by a configuration option (`option_value`), or `default_path()` (e.g.
/// arm::defaultArmModelPath) when the option was not given (empty).
std::filesystem::path configPathOr(const std::string& option_value, std::filesystem::path (*default_path)());

/// The model names of the joints `names` (short or model names) of `gains`, in the order given;
/// every joint of the file when `names` is empty.
/// @throws core::ConfigError with key path `option` for a joint the file lacks or a joint named
///   twice (also as "EB" and "R_EB").
std::vector<std::string> gainsJointNames(const controllers::GainsConfig& gains, const std::vector<std::string>& names,
                                         const std::string& option);

/// A number for a message: up to 6 significant digits, no trailing zeros ("0.001", "3000").
std::string numberText(double value);

/// A joint's model name without its "R_" side prefix ("R_EB" -> "EB"), as reports and
/// command-line options name joints.
std::string shortJointName(const std::string& name);

}  // namespace fullarm::app
