#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

namespace fullarm::test {

/// The scratch folders this test process made, deleted when the process ends normally unless a
/// test failed (then they stay for a look, and the failure output names them) or
/// FULLARM_KEEP_SCRATCH is set in the environment.
class ScratchRegistry {
 public:
  static ScratchRegistry& instance() {
    static ScratchRegistry registry;
    return registry;
  }

  void add(const std::filesystem::path& dir) {
    const std::lock_guard<std::mutex> lock(mutex_);
    dirs_.push_back(dir);
  }

  ScratchRegistry(const ScratchRegistry&) = delete;
  ScratchRegistry& operator=(const ScratchRegistry&) = delete;

  ~ScratchRegistry() {
    // Constructed on the first scratch folder, inside a test, so after gtest's own singleton:
    // it is destroyed before that one and may still ask whether anything failed.
    // A forked child that exits runs this too: only the process that made the folders removes them.
    if (::getpid() != owner_) return;
    const bool keep = std::getenv("FULLARM_KEEP_SCRATCH") != nullptr || ::testing::UnitTest::GetInstance()->Failed();
    if (keep) return;
    for (const std::filesystem::path& dir : dirs_) {
      std::error_code ignored;
      std::filesystem::remove_all(dir, ignored);
    }
  }

 private:
  ScratchRegistry() : owner_(::getpid()) {}
  pid_t owner_;
  std::mutex mutex_;
  std::vector<std::filesystem::path> dirs_;
};

/// A fresh, empty scratch folder `<tmp>/<name>_<pid>` for one test.
///
/// The process id keeps two concurrent runs of the suites (two build trees, a CI clone beside a
/// developer's build) out of each other's files. Whatever the folder held is deleted first, and
/// the folder itself when the test process ends (see ScratchRegistry).
inline std::filesystem::path scratchDir(std::string_view name) {
  std::string leaf(name);
  leaf.append("_").append(std::to_string(::getpid()));
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / leaf;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  ScratchRegistry::instance().add(dir);
  return dir;
}

}  // namespace fullarm::test
