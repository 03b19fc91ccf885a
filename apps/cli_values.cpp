#include "cli_values.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fullarm/core/config_error.hpp"

namespace fullarm::app {

Eigen::VectorXd parseJointVector(std::string_view text, const arm::ArmModel& model, const std::string& option) {
  std::vector<double> values;
  std::size_t pos = 0;
  while (pos < text.size()) {
    while (pos < text.size() && (text[pos] == ',' || text[pos] == ' ' || text[pos] == '\t')) ++pos;
    if (pos >= text.size()) break;
    std::size_t end = pos;
    while (end < text.size() && text[end] != ',' && text[end] != ' ' && text[end] != '\t') ++end;
    const std::string_view token = text.substr(pos, end - pos);
    double v = 0.0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), v);
    if (ec != std::errc() || ptr != token.data() + token.size() || !std::isfinite(v)) {
      throw core::ConfigError({}, option,
                              "element " + std::to_string(values.size()) + " is '" + std::string(token) +
                                  "': expected a finite number in radians");
    }
    values.push_back(v);
    pos = end;
  }
  if (values.empty() || values.size() > static_cast<std::size_t>(model.numJoints())) {
    throw core::ConfigError({}, option,
                            "expected 1 to " + std::to_string(model.numJoints()) + " joint angles in radians, got " +
                                std::to_string(values.size()));
  }
  Eigen::VectorXd q = model.defaultPosture();
  for (std::size_t i = 0; i < values.size(); ++i) {
    const arm::Joint& j = model.joints[i];
    if (values[i] < j.limits.min_rad || values[i] > j.limits.max_rad) {
      throw core::ConfigError({}, option,
                              "element " + std::to_string(i) + " (" + j.name + ") = " + std::to_string(values[i]) +
                                  " rad is outside the joint range [" + std::to_string(j.limits.min_rad) + ", " +
                                  std::to_string(j.limits.max_rad) + "] rad");
    }
    q[static_cast<Eigen::Index>(i)] = values[i];
  }
  return q;
}

std::filesystem::path configPathOr(const std::string& option_value, std::filesystem::path (*default_path)()) {
  return option_value.empty() ? default_path() : std::filesystem::path(option_value);
}

std::vector<std::string> gainsJointNames(const controllers::GainsConfig& gains, const std::vector<std::string>& names,
                                         const std::string& option) {
  std::vector<std::string> out;
  if (names.empty()) {
    for (const controllers::JointGains& g : gains.joints) out.push_back(g.name);
    return out;
  }
  for (const std::string& n : names) {
    std::string model_name;
    try {
      model_name = gains.joints[static_cast<std::size_t>(controllers::findGainsJoint(gains, n))].name;
    } catch (const core::ConfigError& e) {
      throw core::ConfigError({}, option, std::string(e.what()));
    }
    if (std::find(out.begin(), out.end(), model_name) != out.end()) {
      throw core::ConfigError({}, option, "names joint " + model_name + " twice: expected each joint at most once");
    }
    out.push_back(model_name);
  }
  return out;
}

std::string numberText(double value) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", value);
  return text;
}

std::string shortJointName(const std::string& name) {
  return name.starts_with("R_") ? name.substr(2) : name;
}

}  // namespace fullarm::app
