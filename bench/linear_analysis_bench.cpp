// Cost of the linear analysis of one DTS joint (design/linear_analysis.hpp), per joint of
// the default arm: prepareJoint (trim, analytic linearisation, two ZOH discretisations),
// closedLoopSpectralRadius (what a tuner evaluates per candidate) and analyzePrepared (all
// checks: margins on a 600-point grid, rendered impedance, gain limits). The peer in the same
// run is what a simulation-based check of the same joint costs: 1 s of the nonlinear CVODES
// plant in closed loop with stepJointController at 1 kHz.

#include <benchmark/benchmark.h>

#include <cmath>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/controllers/joint_controller.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace {

using namespace fullarm;
using namespace fullarm::controllers;
using namespace fullarm::design;

const arm::ArmModel& model() {
  static const arm::ArmModel m = arm::loadArmModel(arm::defaultArmModelPath());
  return m;
}
const plant::PlantConfig& plantConfig() {
  static const plant::PlantConfig c = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model());
  return c;
}
const GainsConfig& gains() {
  static const GainsConfig g = loadGainsConfig(defaultGainsConfigPath(), model());
  return g;
}

plant::UserArmParams user() {
  plant::UserArmParams u = plantConfig().user_arm;
  u.enabled = true;
  return u;
}

JointPlantModel jointModel(int k) {
  JointPlantModel jm;
  jm.joint = plantConfig().joints[static_cast<std::size_t>(k)];
  const int idx = model().jointIndex(jm.joint.name);
  jm.load = jointLoadFromArm(model(), user(), idx, model().defaultPosture());
  return jm;
}

OperatingPoint trim(const JointPlantModel& jm) {
  return solveOperatingPoint(jm, model().defaultPosture()[model().jointIndex(jm.joint.name)]);
}

void prepare(benchmark::State& state) {
  const JointPlantModel jm = jointModel(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    PreparedJoint p = prepareJoint(jm, trim(jm), LoopSetup{});
    benchmark::DoNotOptimize(p);
  }
  state.SetLabel(jm.joint.name);
}

void spectralRadius(benchmark::State& state) {
  const JointPlantModel jm = jointModel(static_cast<int>(state.range(0)));
  const PreparedJoint p = prepareJoint(jm, trim(jm), LoopSetup{});
  const JointGains& g = gains().joints[static_cast<std::size_t>(state.range(0))];
  for (auto _ : state) benchmark::DoNotOptimize(closedLoopSpectralRadius(p, g, VirtualWall{}));
  state.SetLabel(jm.joint.name);
}

void fullAnalysis(benchmark::State& state) {
  const JointPlantModel jm = jointModel(static_cast<int>(state.range(0)));
  const PreparedJoint p = prepareJoint(jm, trim(jm), LoopSetup{});
  const JointGains& g = gains().joints[static_cast<std::size_t>(state.range(0))];
  for (auto _ : state) {
    LinearChecks c = analyzePrepared(p, g, VirtualWall{}, false);
    benchmark::DoNotOptimize(c);
  }
  state.SetLabel(jm.joint.name);
}

// Peer: one second of the nonlinear plant in closed loop (one sample of delay).
void nonlinearSecond(benchmark::State& state) {
  const int k = static_cast<int>(state.range(0));
  const JointPlantModel jm = jointModel(k);
  const OperatingPoint op = trim(jm);
  const JointGains& g = gains().joints[static_cast<std::size_t>(k)];
  const JointControllerModel cm = makeJointControllerModel(g, ControllerKind::kAdmittance, 1e-3);
  plant::ArmPlant p;
  p.configure(model(), {jm.joint}, model().defaultPosture(), user(), plantConfig().solver, 1);
  const double ga = jm.load.gravity_cos_nm + jm.load.user_gravity_cos_nm;
  const double gb = jm.load.gravity_sin_nm + jm.load.user_gravity_sin_nm;
  for (auto _ : state) {
    std::vector<plant::JointState> init(1);
    init[0] = {op.state[kSpool], 0.0, op.state[kPressureA], op.state[kPressureB], op.state[kAngle], 0.0};
    p.reset(init);
    JointControllerData d;
    resetJointController(cm, d, op.q_rad);
    plant::PlantCommand cmd = plant::PlantCommand::zero(1);
    double pending = op.command;
    for (int i = 0; i < 1000; ++i) {
      cmd.command[0] = pending;
      cmd.tau_user_nm[0] = i < 20 ? 0.5 : 0.0;
      p.step(1e-3, cmd);
      const double q = p.measurement(0).q_rad;
      const JointInput in{q, p.measurement(0).tau_nm, 0.0, ga * std::cos(q) + gb * std::sin(q)};
      pending = op.command + stepJointController(cm, d, in);
    }
    benchmark::DoNotOptimize(p.state(0));
  }
  state.SetLabel(jm.joint.name);
}

BENCHMARK(prepare)->DenseRange(0, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(spectralRadius)->DenseRange(0, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(fullAnalysis)->DenseRange(0, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(nonlinearSecond)->Arg(3)->Arg(6)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
