#include "fullarm/core/config_error.hpp"

#include <sstream>

namespace fullarm::core {
namespace {

std::string formatConfigError(const std::filesystem::path& file, const std::string& key_path,
                              const std::string& message, int line) {
  std::ostringstream text;
  text << (file.empty() ? std::string("<input>") : file.string());
  if (line > 0) text << ':' << line;
  text << ": ";
  if (!key_path.empty()) text << key_path << ": ";
  text << message;
  return text.str();
}

}  // namespace

ConfigError::ConfigError(std::filesystem::path file, std::string key_path, std::string message, int line)
    : std::runtime_error(formatConfigError(file, key_path, message, line)),
      file_(std::move(file)),
      key_path_(std::move(key_path)),
      message_(std::move(message)),
      line_(line) {}

}  // namespace fullarm::core
