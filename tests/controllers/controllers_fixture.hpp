#pragma once
// The default DTS arm model, plant and gains, loaded once per test binary.

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::controllers::test {

inline const arm::ArmModel& dtsModel() {
  static const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  return model;
}

inline const plant::PlantConfig& dtsPlant() {
  static const plant::PlantConfig config = plant::loadPlantConfig(plant::defaultPlantConfigPath(), dtsModel());
  return config;
}

inline const GainsConfig& dtsGains() {
  static const GainsConfig config = loadGainsConfig(defaultGainsConfigPath(), dtsModel());
  return config;
}

}  // namespace fullarm::controllers::test
