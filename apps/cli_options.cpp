#include "cli_options.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <sstream>

namespace fullarm::app {
namespace {

// Shortest text that reads back as `value` ("0.001", "3600", "1e+06").
std::string shortNumber(double value) {
  std::ostringstream out;
  out.precision(6);
  out << value;
  return out.str();
}

std::string rangeText(double min, double max, const std::string& unit) {
  std::string text = "[" + shortNumber(min) + ", " + shortNumber(max) + "]";
  if (!unit.empty()) text += " " + unit;
  return text;
}

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t");
  if (first == std::string::npos) return {};
  const auto last = text.find_last_not_of(" \t");
  return text.substr(first, last - first + 1);
}

// The whole of `text` as a double, or nullopt.
std::optional<double> parseDouble(const std::string& text) {
  const std::string t = trim(text);
  if (t.empty()) return std::nullopt;
  double value = 0.0;
  const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), value);
  if (error != std::errc() || end != t.data() + t.size()) return std::nullopt;
  return value;
}

CLI::Validator numberValidator(double min, double max, const std::string& unit) {
  const std::string expected = "a finite number in " + rangeText(min, max, unit);
  return CLI::Validator(
      [=](std::string& input) -> std::string {
        const std::optional<double> value = parseDouble(input);
        if (!value || !std::isfinite(*value) || *value < min || *value > max) {
          return "expected " + expected + ", got '" + input + "'";
        }
        return {};
      },
      "in " + rangeText(min, max, unit), "fullarm-number");
}

CLI::Validator integerValidator(std::int64_t min, std::int64_t max) {
  const std::string expected = "an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  return CLI::Validator(
      [=](std::string& input) -> std::string {
        const std::string t = trim(input);
        std::int64_t value = 0;
        const auto [end, error] = std::from_chars(t.data(), t.data() + t.size(), value);
        if (t.empty() || error != std::errc() || end != t.data() + t.size() || value < min || value > max) {
          return "expected " + expected + ", got '" + input + "'";
        }
        return {};
      },
      "in [" + std::to_string(min) + ", " + std::to_string(max) + "]", "fullarm-integer");
}

CLI::Validator listValidator() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        const std::vector<std::string> items = splitList(input);
        std::set<std::string> seen;
        for (std::size_t i = 0; i < items.size(); ++i) {
          if (items[i].empty()) {
            return "expected comma-separated names with none empty, got '" + input + "' (entry " +
                   std::to_string(i + 1) + " is empty)";
          }
          if (!seen.insert(items[i]).second) {
            return "expected comma-separated names with none repeated, got '" + input + "' ('" + items[i] + "' twice)";
          }
        }
        return {};
      },
      "comma-separated, none repeated", "fullarm-list");
}

CLI::Validator numberListValidator() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        std::size_t count = 0;
        std::size_t pos = 0;
        while (pos < input.size()) {
          const std::size_t end = input.find_first_of(", \t", pos);
          const std::string token = input.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
          if (!token.empty()) {
            const std::optional<double> value = parseDouble(token);
            if (!value || !std::isfinite(*value)) {
              // Elements count from 0, as the joint-range messages (cli_values.hpp) count them.
              return "element " + std::to_string(count) + " is '" + token +
                     "': expected finite numbers separated by commas or spaces, got '" + input + "'";
            }
            ++count;
          } else if (end != std::string::npos && input[end] == ',' && (pos == 0 || input[pos - 1] == ',')) {
            return "expected finite numbers separated by commas or spaces, got '" + input + "' (an empty element)";
          }
          if (end == std::string::npos) break;
          pos = end + 1;
        }
        if (count == 0) return "expected at least one number, got '" + input + "'";
        return {};
      },
      "numbers", "fullarm-number-list");
}

CLI::Validator choiceValidator(const std::vector<std::string>& choices) {
  std::string joined;
  for (const std::string& c : choices) joined += (joined.empty() ? "" : " | ") + c;
  return CLI::Validator(
      [=](std::string& input) -> std::string {
        if (std::find(choices.begin(), choices.end(), input) == choices.end()) {
          return "expected one of " + joined + ", got '" + input + "'";
        }
        return {};
      },
      joined, "fullarm-choice");
}

CLI::Validator fileValidator() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        std::error_code error;
        if (input.empty() || !std::filesystem::is_regular_file(input, error)) {
          return "expected an existing file, got '" + input + "'";
        }
        return {};
      },
      "FILE", "fullarm-file");
}

CLI::Validator folderValidator() {
  return CLI::Validator(
      [](std::string& input) -> std::string {
        if (trim(input).empty()) return "expected an output folder, got '" + input + "'";
        std::error_code error;
        if (std::filesystem::exists(input, error) && !std::filesystem::is_directory(input, error)) {
          return "expected an output folder, got '" + input + "', which is a file";
        }
        return {};
      },
      "FOLDER", "fullarm-folder");
}

}  // namespace

std::vector<std::string> splitList(const std::string& text) {
  std::vector<std::string> items;
  std::size_t pos = 0;
  while (true) {
    const std::size_t comma = text.find(',', pos);
    items.push_back(trim(text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos)));
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return items;
}

std::string commandPath(const CLI::App& command) {
  std::string path;
  for (const CLI::App* app = &command; app != nullptr && app->get_parent() != nullptr; app = app->get_parent()) {
    path = path.empty() ? app->get_name() : app->get_name() + " " + path;
  }
  return path;
}

OptionDeclarer::OptionDeclarer(CLI::App& command, OptionTable& table)
    : command_(command), table_(table), path_(commandPath(command)) {}

OptionSpec& OptionDeclarer::record(const std::string& name, OptionKind kind) {
  OptionSpec spec;
  spec.command = path_;
  // The long name: the first "--" alternative of a CLI11 name list ("--a,!--no-a" -> "--a").
  std::string first = name.substr(0, name.find(','));
  if (!first.empty() && first.front() == '!') first.erase(0, 1);
  spec.name = first;
  spec.kind = kind;
  return table_.add(std::move(spec));
}

CLI::Option* OptionDeclarer::number(const std::string& name, double& value, const std::string& description,
                                    NumberRange range) {
  OptionSpec& spec = record(name, OptionKind::kNumber);
  spec.min = range.min;
  spec.max = range.max;
  spec.unit = range.unit;
  return command_.add_option(name, value, description)
      ->check(numberValidator(range.min, range.max, range.unit))
      ->capture_default_str();
}

CLI::Option* OptionDeclarer::number(const std::string& name, std::optional<double>& value,
                                    const std::string& description, NumberRange range) {
  OptionSpec& spec = record(name, OptionKind::kNumber);
  spec.min = range.min;
  spec.max = range.max;
  spec.unit = range.unit;
  return command_.add_option(name, value, description)->check(numberValidator(range.min, range.max, range.unit));
}

namespace {

template <typename T>
CLI::Option* addInteger(CLI::App& command, OptionSpec& spec, const std::string& name, T& value,
                        const std::string& description, std::int64_t min, std::int64_t max) {
  spec.min = static_cast<double>(min);
  spec.max = static_cast<double>(max);
  return command.add_option(name, value, description)->check(integerValidator(min, max));
}

}  // namespace

CLI::Option* OptionDeclarer::integer(const std::string& name, int& value, const std::string& description,
                                     std::int64_t min, std::int64_t max) {
  return addInteger(command_, record(name, OptionKind::kInteger), name, value, description, min, max)
      ->capture_default_str();
}

CLI::Option* OptionDeclarer::integer(const std::string& name, std::optional<int>& value, const std::string& description,
                                     std::int64_t min, std::int64_t max) {
  return addInteger(command_, record(name, OptionKind::kInteger), name, value, description, min, max);
}

CLI::Option* OptionDeclarer::integer(const std::string& name, std::int64_t& value, const std::string& description,
                                     std::int64_t min, std::int64_t max) {
  return addInteger(command_, record(name, OptionKind::kInteger), name, value, description, min, max)
      ->capture_default_str();
}

CLI::Option* OptionDeclarer::integer(const std::string& name, std::optional<std::int64_t>& value,
                                     const std::string& description, std::int64_t min, std::int64_t max) {
  return addInteger(command_, record(name, OptionKind::kInteger), name, value, description, min, max);
}

CLI::Option* OptionDeclarer::integer(const std::string& name, std::uint64_t& value, const std::string& description,
                                     std::int64_t min, std::int64_t max) {
  return addInteger(command_, record(name, OptionKind::kInteger), name, value, description, min, max)
      ->capture_default_str();
}

CLI::Option* OptionDeclarer::list(const std::string& name, std::vector<std::string>& values,
                                  const std::string& description) {
  record(name, OptionKind::kList);
  return command_
      .add_option_function<std::string>(
          name, [&values](const std::string& text) { values = splitList(text); }, description)
      ->check(listValidator());
}

CLI::Option* OptionDeclarer::list(const std::string& name, std::string& text, const std::string& description) {
  record(name, OptionKind::kList);
  return command_.add_option(name, text, description)->check(listValidator());
}

CLI::Option* OptionDeclarer::numberList(const std::string& name, std::string& text, const std::string& description) {
  record(name, OptionKind::kNumberList);
  return command_.add_option(name, text, description)->check(numberListValidator());
}

CLI::Option* OptionDeclarer::choice(const std::string& name, std::string& value, const std::string& description,
                                    std::vector<std::string> choices) {
  OptionSpec& spec = record(name, OptionKind::kChoice);
  spec.choices = choices;
  return command_.add_option(name, value, description)->check(choiceValidator(choices))->capture_default_str();
}

CLI::Option* OptionDeclarer::name(const std::string& option, std::string& value, const std::string& description) {
  record(option, OptionKind::kName);
  return command_.add_option(option, value, description)
      ->check(CLI::Validator(
          [](std::string& input) -> std::string {
            return trim(input).empty() ? "expected a name, got '" + input + "'" : std::string();
          },
          "NAME", "fullarm-name"))
      ->capture_default_str();
}

CLI::Option* OptionDeclarer::file(const std::string& name, std::string& path, const std::string& description) {
  record(name, OptionKind::kFile);
  return command_.add_option(name, path, description)->check(fileValidator());
}

CLI::Option* OptionDeclarer::files(const std::string& name, std::vector<std::string>& paths,
                                   const std::string& description) {
  record(name, OptionKind::kFile);
  return command_.add_option(name, paths, description)->check(fileValidator());
}

CLI::Option* OptionDeclarer::folder(const std::string& name, std::string& path, const std::string& description) {
  record(name, OptionKind::kFolder);
  return command_.add_option(name, path, description)->check(folderValidator());
}

CLI::Option* OptionDeclarer::flag(const std::string& name, bool& value, const std::string& description) {
  record(name, OptionKind::kFlag);
  return command_.add_flag(name, value, description);
}

}  // namespace fullarm::app
