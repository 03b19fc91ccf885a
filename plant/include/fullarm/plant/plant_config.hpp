#pragma once
/// @file
/// Loading the hydraulic plant parameters (config/dts_plant.yaml; schema in docs/plant.md).
/// Joint limits, cylinder levers and sensor calibrations come from the arm model; the file
/// holds everything hydraulic.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/joint_params.hpp"

namespace fullarm::plant {

/// The plant configuration: one JointParams per arm joint (model order), solver settings,
/// the user arm at the cuff and the sensor noise seed.
struct PlantConfig {
  std::filesystem::path source;
  std::vector<JointParams> joints;
  SolverOptions solver{};
  UserArmParams user_arm{};
  std::uint64_t seed = 1;
};

/// Loads and validates a plant file for `model` (strict: missing and unknown keys are errors).
/// @throws core::ConfigError naming the file, line, key path and what was expected.
[[nodiscard]] PlantConfig loadPlantConfig(const std::filesystem::path& file, const arm::ArmModel& model);

/// Parses plant YAML text; `source` names it in errors.
/// @throws core::ConfigError
[[nodiscard]] PlantConfig parsePlantConfig(std::string_view yaml_text, const std::filesystem::path& source,
                                           const arm::ArmModel& model);

/// Writes `config` as plant YAML (the schema loadPlantConfig reads, docs/plant.md) with 17
/// significant digits, so that parsePlantConfig of the text with the same `model` gives the same
/// doubles. The supply, return and fluid sections are written from the first joint (the loader
/// gives every joint the same ones); `header` lines are written first as comments. Settings the
/// schema does not hold (SolverOptions::rigid_derivatives_once_per_period, and what comes from
/// the arm model: limits, levers, calibrations) are not written.
/// @throws std::invalid_argument when `config` has no joints, its joints differ in supply or
///   fluid, or its user arm's link is not a joint of `model`.
[[nodiscard]] std::string formatPlantConfigYaml(const PlantConfig& config, const arm::ArmModel& model,
                                                const std::vector<std::string>& header = {});

/// $FULLARM_CONFIG_DIR/dts_plant.yaml if set, else the source-tree or installed config folder.
[[nodiscard]] std::filesystem::path defaultPlantConfigPath();

/// Index in config.joints of the joint called `name`; accepts the model name ("R_EB") or
/// the short name ("EB").
/// @throws core::ConfigError listing the known names when there is no such joint.
[[nodiscard]] int findPlantJoint(const PlantConfig& config, std::string_view name);

}  // namespace fullarm::plant
