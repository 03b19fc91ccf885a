#pragma once
// Writing a command's output folder: any failure there (a folder that cannot be created, a full
// disk) is the user's to fix, so it becomes an OutputError (exit code 2) naming the path, never
// an internal error.

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>

#include "fullarm/reports/report.hpp"

namespace fullarm::app {

/// An output file or folder could not be written; what() names the path and the cause.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Runs `write` (which writes `path`), turning any exception into an OutputError naming `path`.
template <typename Write>
void writeOutput(const std::filesystem::path& path, Write&& write) {
  try {
    std::forward<Write>(write)();
  } catch (const OutputError&) {
    throw;
  } catch (const std::exception& e) {
    const std::string cause = e.what();
    throw OutputError(cause.find(path.string()) != std::string::npos ? cause
                                                                     : "cannot write " + path.string() + ": " + cause);
  }
}

/// report.write(out_dir) as writeOutput.
inline void writeReport(const reports::Report& report, const std::filesystem::path& out_dir) {
  writeOutput(out_dir, [&] { report.write(out_dir); });
}

/// `text` into `path` (its folder created), as writeOutput.
void writeTextFile(const std::filesystem::path& path, const std::string& text);

/// Creates `folder` (and its parents) for a command's output, as writeOutput.
void createOutputFolder(const std::filesystem::path& folder);

}  // namespace fullarm::app
