#pragma once
/// @file
/// Configuration-time errors that name the file, the key path and what was expected.

#include <filesystem>
#include <stdexcept>
#include <string>

namespace fullarm::core {

/// Thrown when a configuration file (YAML) or a configuration value is invalid.
///
/// what() reads `<file>:<line>: <key.path>: <message>`; the parts are also available
/// separately so a caller can format them differently.
class ConfigError : public std::runtime_error {
 public:
  /// @param file     the file that holds the bad value (may be empty for values from code
  ///                 or the command line)
  /// @param key_path dotted key path, e.g. `joints[2].limits.min_rad`
  /// @param message  what is wrong and what was expected
  /// @param line     1-based line in the file, or 0 when unknown
  ConfigError(std::filesystem::path file, std::string key_path, std::string message, int line = 0);

  [[nodiscard]] const std::filesystem::path& file() const noexcept { return file_; }
  [[nodiscard]] const std::string& keyPath() const noexcept { return key_path_; }
  [[nodiscard]] const std::string& message() const noexcept { return message_; }
  [[nodiscard]] int line() const noexcept { return line_; }

 private:
  std::filesystem::path file_;
  std::string key_path_;
  std::string message_;
  int line_;
};

}  // namespace fullarm::core
