#pragma once
// The default DTS arm model and gains, loaded once per test binary.

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"

namespace fullarm::controllers::test {

inline const arm::ArmModel& dtsModel() {
  static const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  return model;
}

inline const GainsConfig& dtsGains() {
  static const GainsConfig config = loadGainsConfig(defaultGainsConfigPath(), dtsModel());
  return config;
}

}  // namespace fullarm::controllers::test
