#pragma once
/// @file
/// The identification settings (config/identification.yaml): the fit's parameter bounds and
/// scaling, its global stage and polish (and the polish's Jacobian), the per-experiment initial
/// states, and the validation thresholds. Strict: missing and
/// unknown keys are errors naming the file, the line and the key path.

#include <filesystem>
#include <string_view>

#include "fullarm/identification/grey_box.hpp"
#include "fullarm/identification/validation.hpp"

namespace fullarm::identification {

/// The settings of one identification.
struct IdentificationConfig {
  std::filesystem::path source;
  FitOptions fit;  ///< bounds, scaling, stages, Jacobian and initial states (no progress callback)
  ValidationThresholds validation;
  double coulomb_smoothing_radps = 0.05;  ///< the reduced model's w_eps
  double stribeck_velocity_radps = 0.05;  ///< the reduced model's w_s
};

/// Parses the YAML text; `source` names it in errors.
/// @throws core::ConfigError for a missing or unknown key, a log-scaled parameter with a
///   non-positive bound, min > max, initial-state bounds that do not hold 0, or a value out of
///   range
[[nodiscard]] IdentificationConfig parseIdentificationConfig(std::string_view yaml_text,
                                                             const std::filesystem::path& source);

/// Loads a file (see parseIdentificationConfig). @throws core::ConfigError
[[nodiscard]] IdentificationConfig loadIdentificationConfig(const std::filesystem::path& file);

/// $FULLARM_CONFIG_DIR/identification.yaml if set, else the source-tree or installed config folder.
[[nodiscard]] std::filesystem::path defaultIdentificationConfigPath();

}  // namespace fullarm::identification
