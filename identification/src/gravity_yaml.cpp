#include "fullarm/identification/gravity_yaml.hpp"

#include <cstdio>
#include <regex>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace fullarm::identification {
namespace {

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
  const std::regex name_line(R"(^\s*- name:\s*([A-Za-z0-9_]+))");
  const std::regex inertia_entry(R"((xx|yy|zz|xy|xz|yz):\s*([-+0-9.eE]+))");
  for (std::size_t j = 0; j < source.joints.size(); ++j) {
    const auto& before = source.joints[j];
    const auto& after = fitted.joints[j];
    if (before.name != after.name) throw std::invalid_argument(source_name + ": joint order differs at " + before.name);
    if (before.inertial.mass_kg == after.inertial.mass_kg && before.inertial.com_m == after.inertial.com_m) continue;
    // The joint's block: from its `- name:` line to the next one.
    std::size_t begin = lines.size();
    for (std::size_t i = 0; i < lines.size(); ++i) {
      std::smatch m;
      if (std::regex_search(lines[i], m, name_line) && m[1] == before.name) {
        begin = i;
        break;
      }
    }
    if (begin == lines.size()) throw std::invalid_argument(source_name + ": no '- name: " + before.name + "' line");
    std::size_t end = begin + 1;
    while (end < lines.size() && !std::regex_search(lines[end], name_line)) ++end;
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
        std::string out;
        auto it = std::sregex_iterator(line.begin(), line.end(), inertia_entry);
        std::size_t last = 0;
        for (; it != std::sregex_iterator(); ++it) {
          out += line.substr(last, static_cast<std::size_t>(it->position()) - last);
          out += (*it)[1].str() + ": " + number(std::stod((*it)[2].str()) * ratio);
          last = static_cast<std::size_t>(it->position() + it->length());
        }
        out += line.substr(last);
        const std::size_t hash = out.find('#');
        if (hash != std::string::npos) out.insert(hash + 1, " scaled to the fitted mass from:");
        line = out;
        inertia_done = true;
      }
    }
    if (!(mass_done && com_done && inertia_done)) {
      throw std::invalid_argument(source_name + ": joint " + before.name +
                                  " has no mass_kg, com_m and inertia_kgm2 lines to rewrite");
    }
  }
  std::string text;
  for (const auto& line : lines) text.append(line).append("\n");
  return text;
}

}  // namespace fullarm::identification
