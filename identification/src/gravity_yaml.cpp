#include "fullarm/identification/gravity_yaml.hpp"

#include <cctype>
#include <charconv>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace fullarm::identification {
namespace {

/// The first words of the header armYamlWithGravity writes.
const std::string kHeaderStart = "# The arm file ";

std::string number(double v) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.10g", v == 0.0 ? 0.0 : v);  // no "-0"
  std::string s(buffer);
  if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
  return s;
}

/// The leading spaces and the key of a `key: value` line ("" when the line is something else).
std::string indentOf(const std::string& line, const std::string& key) {
  const std::size_t at = line.find(key + ":");
  if (at == std::string::npos) return {};
  for (std::size_t i = 0; i < at; ++i) {
    if (line[i] != ' ') return {};
  }
  return line.substr(0, at);
}

/// The joint name of a `- name: X` line ("" for any other line).
std::string nameOf(const std::string& line) {
  std::size_t i = line.find_first_not_of(' ');
  if (i == std::string::npos || line.compare(i, 7, "- name:") != 0) return {};
  i = line.find_first_not_of(' ', i + 7);
  if (i == std::string::npos) return {};
  std::size_t end = i;
  while (end < line.size() && (std::isalnum(static_cast<unsigned char>(line[end])) != 0 || line[end] == '_')) ++end;
  return line.substr(i, end - i);
}

/// `line` (an `inertia_kgm2: {xx: v, ...}` line) with every entry's number times `ratio`.
std::string scaleInertiaLine(const std::string& line, double ratio) {
  const std::size_t open = line.find('{');
  const std::size_t close = line.find('}', open == std::string::npos ? 0 : open);
  if (open == std::string::npos || close == std::string::npos) return {};
  std::string out = line.substr(0, open + 1);
  std::size_t i = open + 1;
  while (i < close) {
    const std::size_t colon = line.find(':', i);
    if (colon == std::string::npos || colon > close) return {};
    out += line.substr(i, colon + 1 - i);
    const std::size_t v = line.find_first_not_of(' ', colon + 1);
    if (v == std::string::npos || v >= close) return {};
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(line.data() + v, line.data() + close, value);
    if (ec != std::errc()) return {};
    out += ' ';
    out += number(value * ratio);
    i = static_cast<std::size_t>(ptr - line.data());
    const std::size_t comma = line.find(',', i);
    if (comma == std::string::npos || comma > close) {
      out += line.substr(i, close - i);
      break;
    }
    out += line.substr(i, comma + 1 - i);
    i = comma + 1;
  }
  out += line.substr(close);
  return out;
}

}  // namespace

std::string armYamlWithGravity(std::string_view yaml_text, const std::string& source_name, const arm::ArmModel& source,
                               const arm::ArmModel& fitted, std::string_view note) {
  if (source.joints.size() != fitted.joints.size()) {
    throw std::invalid_argument(source_name + ": the fitted model has " + std::to_string(fitted.joints.size()) +
                                " joints, the arm file " + std::to_string(source.joints.size()));
  }
  std::vector<std::string> lines;
  {
    std::istringstream in{std::string(yaml_text)};
    for (std::string line; std::getline(in, line);) lines.push_back(line);
  }
  // A source that is itself a written file: its header (up to the first bare "#") described an
  // earlier fit and gives way to this one's.
  if (!lines.empty() && lines.front().rfind(kHeaderStart, 0) == 0) {
    std::size_t end = 0;
    while (end < lines.size() && lines[end] != "#") ++end;
    if (end < lines.size()) lines.erase(lines.begin(), lines.begin() + static_cast<std::ptrdiff_t>(end + 1));
  }
  for (std::size_t j = 0; j < source.joints.size(); ++j) {
    const auto& before = source.joints[j];
    const auto& after = fitted.joints[j];
    if (before.name != after.name) throw std::invalid_argument(source_name + ": joint order differs at " + before.name);
    if (before.inertial.mass_kg == after.inertial.mass_kg && before.inertial.com_m == after.inertial.com_m) continue;
    // The joint's block: from its `- name:` line to the next one.
    std::size_t begin = lines.size();
    for (std::size_t i = 0; i < lines.size(); ++i) {
      if (nameOf(lines[i]) == before.name) {
        begin = i;
        break;
      }
    }
    if (begin == lines.size()) throw std::invalid_argument(source_name + ": no '- name: " + before.name + "' line");
    std::size_t end = begin + 1;
    while (end < lines.size() && nameOf(lines[end]).empty()) ++end;
    bool mass_done = false;
    bool com_done = false;
    bool inertia_done = false;
    const double ratio = before.inertial.mass_kg > 0.0 ? after.inertial.mass_kg / before.inertial.mass_kg : 1.0;
    for (std::size_t i = begin + 1; i < end; ++i) {
      std::string& line = lines[i];
      if (!mass_done && !indentOf(line, "mass_kg").empty()) {
        line = indentOf(line, "mass_kg") + "mass_kg: " + number(after.inertial.mass_kg) + "  # " + std::string(note);
        mass_done = true;
      } else if (!com_done && !indentOf(line, "com_m").empty()) {
        const Eigen::Vector3d& c = after.inertial.com_m;
        line = indentOf(line, "com_m") + "com_m: [" + number(c.x()) + ", " + number(c.y()) + ", " + number(c.z()) + "]";
        com_done = true;
      } else if (!inertia_done && !indentOf(line, "inertia_kgm2").empty()) {
        std::string out = scaleInertiaLine(line, ratio);
        if (out.empty())
          throw std::invalid_argument(source_name + ": joint " + before.name + ": unreadable inertia line");
        const std::size_t hash = out.find('#');
        const std::string prefix = " scaled to the fitted mass from:";
        if (hash != std::string::npos && out.compare(hash + 1, prefix.size(), prefix) != 0)
          out.insert(hash + 1, prefix);
        line = out;
        inertia_done = true;
      }
    }
    if (!(mass_done && com_done && inertia_done)) {
      throw std::invalid_argument(source_name + ": joint " + before.name +
                                  " has no mass_kg, com_m and inertia_kgm2 lines to rewrite");
    }
  }
  // A header that says what this file is: the source's own header below it still describes the
  // source (its kinematics, limits and sensors are unchanged).
  std::string text =
      kHeaderStart + std::filesystem::path(source_name).filename().string() +
      " with the gravity set of the links marked\n# \"" + std::string(note) +
      "\"\n# (mass and centre of mass; their inertias scaled by the mass ratio). Every other line is the\n" +
      "# source's, below.\n#\n";
  for (const auto& line : lines) text.append(line).append("\n");
  return text;
}

}  // namespace fullarm::identification
