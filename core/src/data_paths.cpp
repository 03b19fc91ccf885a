#include "fullarm/core/data_paths.hpp"

#include <cstdlib>
#include <string>
#include <system_error>

#ifndef FULLARM_SOURCE_CONFIG_DIR
#error "FULLARM_SOURCE_CONFIG_DIR must be defined by the build"
#endif
#ifndef FULLARM_INSTALL_CONFIG_DIR
#error "FULLARM_INSTALL_CONFIG_DIR must be defined by the build"
#endif
#ifndef FULLARM_SOURCE_SCENE_DIR
#error "FULLARM_SOURCE_SCENE_DIR must be defined by the build"
#endif
#ifndef FULLARM_INSTALL_SCENE_DIR
#error "FULLARM_INSTALL_SCENE_DIR must be defined by the build"
#endif
#ifndef FULLARM_INSTALL_PREFIX
#error "FULLARM_INSTALL_PREFIX must be defined by the build"
#endif

namespace fullarm::core {

std::filesystem::path defaultDataPath(std::string_view file_name, const char* env_var,
                                      const std::filesystem::path& source_dir,
                                      const std::filesystem::path& installed_dir) {
  if (const char* dir = std::getenv(env_var); dir != nullptr && *dir != '\0') {
    return std::filesystem::path(dir) / file_name;
  }
  const std::filesystem::path installed = installed_dir / file_name;
  const std::filesystem::path source = source_dir / file_name;
  // A program installed under the install prefix reads the installed file; anything else (the
  // build tree's programs and tests) reads the source tree's, when that tree still exists.
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  const std::string prefix = std::filesystem::path(FULLARM_INSTALL_PREFIX).lexically_normal().string() + "/";
  const bool running_installed = !ec && exe.lexically_normal().string().rfind(prefix, 0) == 0;
  if (!running_installed && std::filesystem::is_regular_file(source)) return source;
  if (std::filesystem::is_regular_file(installed)) return installed;
  return source;
}

std::filesystem::path defaultConfigPath(std::string_view file_name) {
  return defaultDataPath(file_name, "FULLARM_CONFIG_DIR", FULLARM_SOURCE_CONFIG_DIR, FULLARM_INSTALL_CONFIG_DIR);
}

std::filesystem::path defaultScenePath(std::string_view file_name) {
  return defaultDataPath(file_name, "FULLARM_SCENE_DIR", FULLARM_SOURCE_SCENE_DIR, FULLARM_INSTALL_SCENE_DIR);
}

}  // namespace fullarm::core
