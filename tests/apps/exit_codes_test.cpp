// The exit codes of `fullarm` (docs/cli.md): which failures are the user's to fix (2) and which
// are fullarm's own (3), and that a run too long for its memory bound is refused before it runs.

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <filesystem>
#include <new>
#include <sstream>
#include <stdexcept>

#include "cli.hpp"
#include "exit_codes.hpp"
#include "fullarm/accessibility/reach.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/haptics/tri_mesh.hpp"
#include "output_files.hpp"

namespace fullarm::app {
namespace {

template <typename E>
int codeOf(const E& error, std::string* message = nullptr) {
  std::ostringstream err;
  const int code = exitCodeForException(std::make_exception_ptr(error), err);
  if (message != nullptr) *message = err.str();
  return code;
}

TEST(ExitCodes, TheDocumentedValues) {
  EXPECT_EQ(kExitPass, 0);
  EXPECT_EQ(kExitFail, 1);
  EXPECT_EQ(kExitBadInput, 2);
  EXPECT_EQ(kExitInternal, 3);
  EXPECT_EQ(kExitInconclusive, 4);
}

TEST(ExitCodes, InputTheUserCanFixIsBadInput) {
  std::string message;
  EXPECT_EQ(codeOf(core::ConfigError("arm.yaml", "joints[2].mass_kg", "expected > 0"), &message), kExitBadInput);
  EXPECT_NE(message.find("joints[2].mass_kg"), std::string::npos) << message;
  EXPECT_EQ(message.find("internal"), std::string::npos) << message;
  EXPECT_EQ(codeOf(haptics::MeshError("wall.dae", "no valid triangle")), kExitBadInput);
  EXPECT_EQ(codeOf(accessibility::ReachInputError("reach limits: max_link_force_n must be >= 0")), kExitBadInput);
  EXPECT_EQ(codeOf(OutputError("cannot write out/report.html: No space left on device")), kExitBadInput);
  EXPECT_EQ(codeOf(std::filesystem::filesystem_error("create_directories", "/proc/x",
                                                     std::make_error_code(std::errc::permission_denied))),
            kExitBadInput);
}

TEST(ExitCodes, EverythingElseIsAnInternalError) {
  std::string message;
  EXPECT_EQ(codeOf(std::runtime_error("CVODES: unexpected flag"), &message), kExitInternal);
  EXPECT_NE(message.find("internal error: CVODES: unexpected flag"), std::string::npos) << message;
  EXPECT_EQ(codeOf(std::invalid_argument("renderQuery: no rendering mode")), kExitInternal);
  EXPECT_EQ(codeOf(std::logic_error("report written twice")), kExitInternal);
  EXPECT_EQ(codeOf(std::bad_alloc(), &message), kExitInternal);
  EXPECT_NE(message.find("out of memory"), std::string::npos) << message;
  EXPECT_EQ(codeOf(42), kExitInternal);
}

TEST(ExitCodes, AnOutputFolderThatCannotBeMadeIsBadInput) {
  // A folder below a regular file cannot be created.
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "fullarm_exit_codes_test_file";
  { std::ofstream(file) << "x"; }
  std::ostringstream out;
  std::ostringstream err;
  const int code = runFullarm({"arm", "show", "--quiet", "--out", (file / "report").string()}, out, err);
  EXPECT_EQ(code, kExitBadInput) << err.str();
  EXPECT_NE(err.str().find((file / "report").string()), std::string::npos) << err.str();
  std::filesystem::remove(file);
}

TEST(ExitCodes, ARunLongerThanItsTraceBoundIsRefusedBeforeItStarts) {
  // 1000 s of the 7-joint arm at 1 kHz is 7,000,007 trace samples, above the 2,000,000 bound.
  const auto start = std::chrono::steady_clock::now();
  std::ostringstream out;
  std::ostringstream err;
  const std::filesystem::path unused = std::filesystem::temp_directory_path() / "fullarm_exit_codes_test_unused";
  const int code = runFullarm({"plant", "simulate", "--arm", "--duration", "1000", "--out", unused.string()}, out, err);
  const double elapsed_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(code, kExitBadInput) << err.str();
  EXPECT_NE(err.str().find("--duration"), std::string::npos) << err.str();
  EXPECT_NE(err.str().find("at most 2000000"), std::string::npos) << err.str();
  EXPECT_LT(elapsed_s, 10.0) << "the run started";
  EXPECT_FALSE(std::filesystem::exists(unused));
}

}  // namespace
}  // namespace fullarm::app
