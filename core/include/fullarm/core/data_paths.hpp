#pragma once
/// @file
/// Where fullarm's shipped data live: the default configuration files (config/) and scenes
/// (scenes/), in the source tree for a build-tree program and under the install prefix for an
/// installed one, overridable by environment variables.

#include <filesystem>
#include <string_view>

namespace fullarm::core {

/// Path of a data file `file_name` shipped with fullarm: $<env_var>/<file_name> if that variable is
/// set and not empty; else, for a program installed under the install prefix, `installed_dir`'s
/// copy; else `source_dir`'s (the source tree the library was built from, while it exists); else
/// the installed one. defaultConfigPath and defaultScenePath are this rule.
[[nodiscard]] std::filesystem::path defaultDataPath(std::string_view file_name, const char* env_var,
                                                    const std::filesystem::path& source_dir,
                                                    const std::filesystem::path& installed_dir);

/// Path of a default configuration file `file_name` (e.g. "dts_plant.yaml"):
/// $FULLARM_CONFIG_DIR/<file_name> if that variable is set; else, for a program installed under
/// the install prefix, the installed config; else the source tree's config/ (when the tree the
/// library was built from still exists), else the installed one.
[[nodiscard]] std::filesystem::path defaultConfigPath(std::string_view file_name);

/// Path of a shipped scene file `file_name` (e.g. "valve_wall.yaml"), by the same rule as
/// defaultConfigPath with $FULLARM_SCENE_DIR and the scenes/ folder.
[[nodiscard]] std::filesystem::path defaultScenePath(std::string_view file_name);

}  // namespace fullarm::core
