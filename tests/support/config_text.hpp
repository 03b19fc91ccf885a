#pragma once
/// @file
/// Helpers for configuration-file tests: read a shipped YAML file, mutate its text, and expect
/// the clear error (core::ConfigError naming file, line, key path and what was expected).
/// Header-only; the test must link fullarm::arm (every config module does).

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include "fullarm/core/config_error.hpp"

namespace fullarm::testing {

/// The whole text of `file` (empty when it cannot be read; the parse that follows then fails).
inline std::string fileText(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// `text` with the first occurrence of `from` at or after offset `start` replaced by `to`. A
/// missing `from` is a test failure (the mutation would otherwise test nothing).
inline std::string replacedFirst(std::string text, const std::string& from, const std::string& to,
                                 std::size_t start = 0) {
  const std::size_t at = text.find(from, start);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

/// Expects `parse()` to throw core::ConfigError whose key path contains `key_fragment`, whose
/// message contains `message_fragment`, which carries a line number, and whose text names
/// `source_name` (the file name `parse` passed to the parser).
template <typename Parse>
void expectConfigError(Parse&& parse, std::string_view source_name, const std::string& key_fragment,
                       const std::string& message_fragment) {
  try {
    parse();
    ADD_FAILURE() << "no error for " << key_fragment;
  } catch (const core::ConfigError& e) {
    EXPECT_NE(e.keyPath().find(key_fragment), std::string::npos) << e.what();
    EXPECT_NE(e.message().find(message_fragment), std::string::npos) << e.what();
    EXPECT_GT(e.line(), 0) << e.what();
    EXPECT_NE(std::string(e.what()).find(source_name), std::string::npos) << e.what();
  }
}

}  // namespace fullarm::testing
