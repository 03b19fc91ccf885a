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
