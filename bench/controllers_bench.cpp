// Controller step for the 7 arm joints of the DTS (the 1 kHz path): the paper's admittance
// controller (Eq. 3-7) against its peer, the simple torque PID of the paper's section 3.3,
// in the same run; and the whole arm step with fullarm::arm's gravity compensation.

#include <benchmark/benchmark.h>

#include <array>
#include <cmath>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/arm_controller.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/controllers/joint_controller.hpp"

namespace {

using namespace fullarm;

constexpr int kJoints = 7;
constexpr int kInputSets = 256;

struct Fixture {
  arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  controllers::GainsConfig gains = controllers::loadGainsConfig(controllers::defaultGainsConfigPath(), model);
  // Seeded, varied inputs so that branches (saturation, passivity) are exercised.
  std::array<std::array<controllers::JointInput, kJoints>, kInputSets> inputs{};
  Fixture() {
    for (int s = 0; s < kInputSets; ++s) {
      for (int j = 0; j < kJoints; ++j) {
        controllers::JointInput& in = inputs[static_cast<std::size_t>(s)][static_cast<std::size_t>(j)];
        in.q_rad = 0.3 * std::sin(0.05 * s + j);
        in.tau_gravity_nm = 5.0 * std::cos(0.03 * s + j);
        in.tau_load_cell_nm = in.tau_gravity_nm - 3.0 * std::sin(0.11 * s + 2 * j);
        in.tau_contact_nm = s % 64 < 20 ? -2.0 : 0.0;
      }
    }
  }
};

const Fixture& fixture() {
  static const Fixture f;
  return f;
}

void jointSteps(benchmark::State& state, controllers::ControllerKind kind) {
  const Fixture& f = fixture();
  std::array<controllers::JointControllerModel, kJoints> models;
  std::array<controllers::JointControllerData, kJoints> data;
  for (int j = 0; j < kJoints; ++j) {
    controllers::JointGains g = f.gains.joints[static_cast<std::size_t>(j)];
    g.passivity.enabled = true;
    g.torque_filter_hz = 100.0;
    models[static_cast<std::size_t>(j)] = controllers::makeJointControllerModel(g, kind, f.gains.control_period_s);
    controllers::resetJointController(models[static_cast<std::size_t>(j)], data[static_cast<std::size_t>(j)], 0.0);
  }
  std::size_t s = 0;
  for (auto _ : state) {
    const auto& set = f.inputs[s];
    double sum = 0.0;
    for (std::size_t j = 0; j < kJoints; ++j) sum += controllers::stepJointController(models[j], data[j], set[j]);
    benchmark::DoNotOptimize(sum);
    s = (s + 1) % kInputSets;
  }
}

void BM_AdmittanceStep7Joints(benchmark::State& state) {
  jointSteps(state, controllers::ControllerKind::kAdmittance);
}
void BM_TorquePidStep7Joints(benchmark::State& state) {
  jointSteps(state, controllers::ControllerKind::kTorquePid);
}

// The whole arm step: gravity g(q) (forward kinematics and the gravity pass), then the 7
// admittance controllers.
void BM_ArmAdmittanceStepWithGravity(benchmark::State& state) {
  const Fixture& f = fixture();
  const controllers::ArmControllerModel c = controllers::makeArmControllerModel(f.gains, f.model);
  arm::ArmData arm_data(f.model);
  controllers::ArmControllerData d;
  Eigen::VectorXd q = f.model.defaultPosture();
  controllers::resetArmController(c, d, q);
  Eigen::VectorXd cells(kJoints), env = Eigen::VectorXd::Zero(f.model.numJoints()), v(kJoints);
  std::size_t s = 0;
  for (auto _ : state) {
    const auto& set = f.inputs[s];
    for (int j = 0; j < kJoints; ++j) {
      q[j] = set[static_cast<std::size_t>(j)].q_rad;
      cells[j] = set[static_cast<std::size_t>(j)].tau_load_cell_nm;
    }
    arm::computeGravityTorques(f.model, arm_data, q);
    controllers::stepArmController(c, d, q, arm_data.tau_gravity, env, cells, v);
    benchmark::DoNotOptimize(v.data());
    s = (s + 1) % kInputSets;
  }
}

BENCHMARK(BM_AdmittanceStep7Joints);
BENCHMARK(BM_TorquePidStep7Joints);
BENCHMARK(BM_ArmAdmittanceStepWithGravity);

}  // namespace

BENCHMARK_MAIN();
