#pragma once

#include <unistd.h>

#include <filesystem>
#include <string>
#include <string_view>

namespace fullarm::test {

/// A fresh, empty scratch folder `<tmp>/<name>_<pid>` for one test.
///
/// The process id keeps two concurrent runs of the suites (two build trees, a CI clone beside a
/// developer's build) out of each other's files. Whatever the folder held is deleted first.
inline std::filesystem::path scratchDir(std::string_view name) {
  std::string leaf(name);
  leaf.append("_").append(std::to_string(::getpid()));
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / leaf;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace fullarm::test
