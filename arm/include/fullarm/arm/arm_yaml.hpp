#pragma once
/// @file
/// Loading the arm model and arm-size files from YAML (schema in docs/arm-model.md).

#include <filesystem>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Loads and validates an arm model. Every key is required unless docs/arm-model.md says
/// otherwise; unknown keys are errors.
/// @throws ConfigError naming the file, the key path and what was expected.
[[nodiscard]] ArmModel loadArmModel(const std::filesystem::path& file);

/// Parses an arm model from YAML text; `source` names it in error messages and resolves
/// relative mesh paths.
/// @throws ConfigError
[[nodiscard]] ArmModel parseArmModel(std::string_view yaml_text, const std::filesystem::path& source);

/// Path of a data file `file_name` shipped with fullarm: $<env_var>/<file_name> if that variable is
/// set and not empty; else, for a program installed under the install prefix, `installed_dir`'s
/// copy; else `source_dir`'s (the source tree the library was built from, while it exists); else
/// the installed one. defaultConfigPath and haptics::defaultScenePath are this rule.
[[nodiscard]] std::filesystem::path defaultDataPath(std::string_view file_name, const char* env_var,
                                                    const std::filesystem::path& source_dir,
                                                    const std::filesystem::path& installed_dir);

/// Path of a default configuration file `file_name` (e.g. "dts_plant.yaml"):
/// $FULLARM_CONFIG_DIR/<file_name> if that variable is set; else, for a program installed under the install prefix, the
/// installed config; else the source tree's config/ (when the tree the library was built from still exists), else the
/// installed one.
[[nodiscard]] std::filesystem::path defaultConfigPath(std::string_view file_name);

/// defaultConfigPath("dts_master.yaml"): the default DTS master model.
[[nodiscard]] std::filesystem::path defaultArmModelPath();

}  // namespace fullarm::arm
