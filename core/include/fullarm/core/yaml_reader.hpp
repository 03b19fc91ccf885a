#pragma once
/// @file
/// Strict YAML reading with errors that name the file, the line and the key path.
/// Every fullarm configuration file is read through these classes: each value is required
/// unless read with an `optional*` call, and finish() rejects keys nobody read.

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "fullarm/core/config_error.hpp"

namespace fullarm::core {

class YamlList;

/// A YAML mapping being read. Copies share the set of keys read so far.
class YamlMap {
 public:
  /// @param node must be a map; otherwise ConfigError is thrown naming `path`.
  YamlMap(const YAML::Node& node, std::string path, std::filesystem::path file);

  /// Parses a whole document; the root must be a map.
  /// @throws ConfigError for a YAML syntax error (with its line) or a non-map root.
  static YamlMap parse(std::string_view text, const std::filesystem::path& file);
  /// Reads and parses a file. @throws ConfigError if it cannot be read.
  static YamlMap load(const std::filesystem::path& file);

  [[nodiscard]] bool has(std::string_view key) const;
  /// A finite number. `unit_hint` goes into the error message ("metres", "rad").
  [[nodiscard]] double number(std::string_view key, std::string_view unit_hint = {}) const;
  [[nodiscard]] std::optional<double> optionalNumber(std::string_view key, std::string_view unit_hint = {}) const;
  [[nodiscard]] int integer(std::string_view key) const;
  [[nodiscard]] std::string string(std::string_view key) const;
  [[nodiscard]] std::optional<std::string> optionalString(std::string_view key) const;
  [[nodiscard]] Eigen::Vector3d vector3(std::string_view key, std::string_view unit_hint = {}) const;
  [[nodiscard]] YamlMap map(std::string_view key) const;
  [[nodiscard]] YamlList list(std::string_view key) const;
  [[nodiscard]] std::optional<YamlList> optionalList(std::string_view key) const;

  /// @throws ConfigError naming the first key that was never read.
  void finish() const;

  /// @throws ConfigError at `<path>.<key>` (or at this map when key is empty).
  [[noreturn]] void fail(std::string_view key, const std::string& message) const;

  [[nodiscard]] const std::string& path() const noexcept { return path_; }
  [[nodiscard]] const std::filesystem::path& file() const noexcept { return file_; }
  [[nodiscard]] const YAML::Node& node() const noexcept { return node_; }

 private:
  [[nodiscard]] YAML::Node get(std::string_view key) const;  // required
  [[nodiscard]] std::string keyPath(std::string_view key) const;

  YAML::Node node_;
  std::string path_;
  std::filesystem::path file_;
  std::shared_ptr<std::set<std::string, std::less<>>> used_;
};

/// A YAML sequence being read.
class YamlList {
 public:
  YamlList(const YAML::Node& node, std::string path, std::filesystem::path file);
  [[nodiscard]] std::size_t size() const { return node_.size(); }
  /// Element `i` as a map (error if it is not one).
  [[nodiscard]] YamlMap map(std::size_t i) const;
  [[nodiscard]] const std::string& path() const noexcept { return path_; }

 private:
  YAML::Node node_;
  std::string path_;
  std::filesystem::path file_;
};

/// 1-based line of the value at a dotted key path such as `joints[2].link.mass_kg` in a parsed
/// document, or 0 when the path does not exist.
[[nodiscard]] int lineOfKeyPath(const YAML::Node& root, std::string_view key_path);

/// Runs `build()` (which reads `root`) and returns its result. A ConfigError thrown without a
/// line (a semantic check that knows only the key path) is rethrown with the line of that key
/// path in `root`'s document; errors that already carry a line pass through unchanged.
/// @throws ConfigError
template <typename Build>
[[nodiscard]] std::invoke_result_t<Build&> withKeyPathLines(const YamlMap& root, Build&& build) {
  try {
    return build();
  } catch (const ConfigError& e) {
    if (e.line() != 0) throw;
    throw ConfigError(e.file(), e.keyPath(), e.message(), lineOfKeyPath(root.node(), e.keyPath()));
  }
}

}  // namespace fullarm::core
