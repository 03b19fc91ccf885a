#pragma once
// Shared fixtures of the hil tests: the default arm, plant, gains and channel map, loaded once,
// and small helpers to build devices and samples.

#include <Eigen/Core>
#include <memory>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/simulated_arm.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::hil::test {

inline const arm::ArmModel& model() {
  return arm::test::defaultModel();
}

inline const plant::PlantConfig& plantConfig() {
  static const plant::PlantConfig config = [] {
    plant::PlantConfig c = plant::loadPlantConfig(arm::test::sourcePath("config/dts_plant.yaml"), model());
    c.solver.integrator = plant::IntegratorKind::kRodas3;  // the lockstep loop's integrator
    return c;
  }();
  return config;
}

inline const DaqConfig& daqConfig() {
  static const DaqConfig config = loadDaqConfig(arm::test::sourcePath("config/dts_daq.yaml"), model());
  return config;
}

/// The shipped plant with chamber pressure transducers on the elbow (joint 3): 0-25 MPa, 16 bits,
/// no noise.
inline plant::PlantConfig plantWithElbowTransducers() {
  plant::PlantConfig c = plantConfig();
  c.joints[3].sensor_noise.pressure_full_scale_pa = 25.0e6;
  c.joints[3].sensor_noise.pressure_bits = 16;
  return c;
}

/// The shipped channel map with the elbow's transducers wired: 0-10 V for 0-25 MPa on analog
/// inputs 7 and 15.
inline DaqConfig daqConfigWithElbowPressures() {
  DaqConfig map = daqConfig();
  map.joints[3].pressure_a = {7, {ChannelCalibration::Kind::kLinear, 1.0, 0.0, 2.5e6, 0.0}};
  map.joints[3].pressure_b = {15, {ChannelCalibration::Kind::kLinear, 1.0, 0.0, 2.5e6, 0.0}};
  return map;
}

/// Half a code of those inputs on the shipped map's +-10 V, 12-bit converter [Pa].
inline constexpr double kElbowPressureHalfCodePa = 0.5 * 2.5e6 * 20.0 / 4095.0;

/// The seven arm joints, the simulated devices' joints.
inline arm::JointSelection armJoints() {
  return arm::JointSelection(model().numJoints(), {0, 1, 2, 3, 4, 5, 6});
}

/// A posture inside every limit.
inline Eigen::VectorXd restPosture() {
  Eigen::VectorXd q = model().defaultPosture();
  q[3] = 1.2;  // elbow bent, well inside every limit
  return q;
}

/// A simulated arm at restPosture() with `latency` periods of I/O latency.
inline std::unique_ptr<SimulatedArm> makeArm(int latency = 1) {
  return std::make_unique<SimulatedArm>(model(), plantConfig(), restPosture(), 1e-3, latency);
}

/// A valid sample of `n` joints at `q` with zero load cells.
inline JointSample sampleAt(const IoVector& q) {
  JointSample s;
  s.q_rad = q;
  s.tau_load_cell_nm = IoVector::Zero(q.size());
  return s;
}

}  // namespace fullarm::hil::test
