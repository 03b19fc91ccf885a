// Runs the `fullarm` program under test (FULLARM_EXE, set by tests/apps/CMakeLists.txt) and
// captures its exit code and output; shared by the command-line test suites.
#pragma once

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "scratch_dir.hpp"

namespace fullarm::test {

struct CliResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr
};

/// Runs `fullarm <args>` through the shell; stderr is merged into the output.
inline CliResult runFullarm(const std::string& args) {
  const std::string command = std::string(FULLARM_EXE) + " " + args + " 2>&1";
  CliResult r;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

/// An empty scratch folder `<tmp>/<suite>_<name>_<pid>`, created afresh (see scratchDir).
inline std::filesystem::path cliTempDir(const std::string& suite, const std::string& name) {
  return scratchDir(suite + "_" + name);
}

}  // namespace fullarm::test
