#pragma once
/// @file
/// Loading the arm model and arm-size files from YAML (schema in docs/arm-model.md).

#include <filesystem>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Loads and validates an arm model. Every key is required unless docs/arm-model.md says
/// otherwise; unknown keys are errors.
/// @throws core::ConfigError naming the file, the key path and what was expected.
[[nodiscard]] ArmModel loadArmModel(const std::filesystem::path& file);

/// Parses an arm model from YAML text; `source` names it in error messages and resolves
/// relative mesh paths.
/// @throws core::ConfigError
[[nodiscard]] ArmModel parseArmModel(std::string_view yaml_text, const std::filesystem::path& source);

/// Index in `joint_names` (model names such as "R_EB") of the joint called `name`, given either
/// as the model name or as the short name without the "R_" side prefix ("EB").
/// @throws core::ConfigError (file `source`, key path `joint`) naming `name` and listing the short
/// names it could have been.
[[nodiscard]] int findJointByName(const std::vector<std::string_view>& joint_names, std::string_view name,
                                  const std::filesystem::path& source);

/// core::defaultConfigPath("dts_master.yaml"): the default DTS master model.
[[nodiscard]] std::filesystem::path defaultArmModelPath();

}  // namespace fullarm::arm
