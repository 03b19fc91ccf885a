#pragma once
// The default DTS arm model, plant and gains, loaded once per test binary.

#include <cmath>
#include <cstddef>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::design::test {

/// Standard deviation of x[begin, end) (population form): the oscillation detector's window
/// statistic, recomputed independently of validation.cpp for the tests that check it.
inline double windowStd(const std::vector<double>& x, std::size_t begin, std::size_t end) {
  double mean = 0.0;
  for (std::size_t i = begin; i < end; ++i) mean += x[i];
  mean /= static_cast<double>(end - begin);
  double var = 0.0;
  for (std::size_t i = begin; i < end; ++i) var += (x[i] - mean) * (x[i] - mean);
  return std::sqrt(var / static_cast<double>(end - begin));
}

inline const arm::ArmModel& dtsModel() {
  static const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  return model;
}

inline const plant::PlantConfig& dtsPlant() {
  static const plant::PlantConfig config = plant::loadPlantConfig(plant::defaultPlantConfigPath(), dtsModel());
  return config;
}

inline const controllers::GainsConfig& dtsGains() {
  static const controllers::GainsConfig config =
      controllers::loadGainsConfig(controllers::defaultGainsConfigPath(), dtsModel());
  return config;
}

/// The default gains file with fixed, hand-sized gains of the development runs (J_m by link
/// size, B_m small, B_o/eps = 5/24 V s/rad, lambda = 300/s, K_m = 20): the closed-loop tests
/// check the harness and the analysis on known loops, independent of later retuning of
/// config/dts_gains.yaml.
inline const controllers::GainsConfig& referenceGains() {
  static const controllers::GainsConfig config = [] {
    controllers::GainsConfig g = dtsGains();
    for (controllers::JointGains& j : g.joints) {
      const bool shoulder = j.name == "R_SFE" || j.name == "R_SAA";
      const bool upper = j.name == "R_HR" || j.name == "R_EB";
      j.impedance.inertia_kgm2 = shoulder ? 0.5 : (upper ? 0.2 : 0.1);
      j.impedance.damping_nms_per_rad = shoulder ? 4.0 : (upper ? 2.0 : 1.0);
      j.impedance.stiffness_nm_per_rad = 20.0;
      j.sliding_mode = {300.0, 5.0, 24.0};
      j.torque_pid = {0.1, 5.0, 0.0, 2.0};
      j.passivity.enabled = false;
      j.torque_filter_hz = 0.0;
      j.error_rate_filter_hz = 0.0;
      j.valve_limit_v = 10.0;
    }
    return g;
  }();
  return config;
}

}  // namespace fullarm::design::test
