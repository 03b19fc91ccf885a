#pragma once
// The default DTS arm model and plant configuration, loaded once per test binary.

#include <string>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::plant::test {

inline const arm::ArmModel& dtsModel() {
  static const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  return model;
}

inline const PlantConfig& dtsPlant() {
  static const PlantConfig config = loadPlantConfig(defaultPlantConfigPath(), dtsModel());
  return config;
}

}  // namespace fullarm::plant::test
