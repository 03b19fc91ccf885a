#pragma once
/// @file
/// The identified model of one joint as a YAML file (`identified.yaml`): the reduced model's
/// parameter groups (grey_box.hpp) with their standard errors, its delay and its fixed channel
/// dynamics. Written with 17 significant digits, so reading it back gives the same doubles; read
/// strictly (missing and unknown keys are errors naming the file, the line and the key path).
/// The same file can serve as the start of another fit.

#include <array>
#include <filesystem>
#include <string>
#include <string_view>

#include "fullarm/identification/grey_box.hpp"

namespace fullarm::identification {

/// An identified joint model.
struct IdentifiedModel {
  std::string joint;  ///< the joint's model name, e.g. "R_EB"
  GreyModel model;
  std::array<double, kGreyParams> standard_error{};  ///< in the parameter's unit (0: fixed)
};

/// The YAML text of `identified` (schema_version 1).
[[nodiscard]] std::string formatIdentifiedModelYaml(const IdentifiedModel& identified);

/// Parses the YAML text; `source` names it in errors.
/// @throws core::ConfigError for a missing or unknown key, a negative standard error, a
///   non-positive value of a positive group, a negative delay or a negative frequency
[[nodiscard]] IdentifiedModel parseIdentifiedModelYaml(std::string_view yaml_text, const std::filesystem::path& source);

/// Loads a file (see parseIdentifiedModelYaml). @throws core::ConfigError
[[nodiscard]] IdentifiedModel loadIdentifiedModel(const std::filesystem::path& file);

}  // namespace fullarm::identification
