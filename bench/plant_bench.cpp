// Real-time factor of the hydraulic plant (simulated seconds per wall second) at a 1 kHz
// control period, one core: one joint (R_EB) and the 7-joint arm, under a 0.5-80 Hz chirp at
// full valve amplitude and under a slow sine, with each integrator (CVODES BDF, the reference;
// Rodas3, the one-step Rosenbrock for real time). Counters per simulated second: integrator
// steps, Jacobian and RHS evaluations, rejected steps (error-test failures), re-initialisations. The peer in the same
// run is a plain RK4 of the same right-hand side at a fixed 10 us step (the step an explicit method needs for the stiff
// joint) to put the BDF figures in proportion.

#include <benchmark/benchmark.h>

#include <numbers>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/rigid_body_dynamics.hpp"
#include "fullarm/arm/rigid_body_reduction.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "fullarm/plant/signals.hpp"

namespace {

using namespace fullarm;
using namespace fullarm::plant;

constexpr double kDt = 1e-3;
constexpr double kDuration = 5.0;

const arm::ArmModel& model() {
  static const arm::ArmModel m = arm::loadArmModel(arm::defaultArmModelPath());
  return m;
}
const PlantConfig& config() {
  static const PlantConfig c = loadPlantConfig(defaultPlantConfigPath(), model());
  return c;
}

SignalParams signal(bool chirp, double full_scale) {
  SignalParams s;
  if (chirp) {
    s.kind = SignalKind::kChirp;
    s.amplitude = full_scale;
    s.start_hz = 0.5;
    s.stop_hz = 80.0;
    s.duration_s = kDuration;
  } else {
    s.kind = SignalKind::kSine;
    s.amplitude = 0.1 * full_scale;
    s.frequency_hz = 0.5;
  }
  return s;
}

void runPlant(benchmark::State& state, bool whole_arm, bool chirp, IntegratorKind integrator,
              bool rigid_derivatives_once_per_period = false) {
  ArmPlant plant;
  std::vector<JointParams> joints;
  if (whole_arm) {
    joints = config().joints;
  } else {
    joints = {config().joints[static_cast<std::size_t>(findPlantJoint(config(), "EB"))]};
  }
  SolverOptions options = config().solver;
  options.integrator = integrator;
  options.rigid_derivatives_once_per_period = rigid_derivatives_once_per_period;
  plant.configure(model(), joints, model().defaultPosture(), UserArmParams{}, options, config().seed);
  const int n = plant.numJoints();
  PlantCommand cmd = PlantCommand::zero(n);
  const SignalParams sig = signal(chirp, 1.0 / joints[0].valve.amplifier_gain_per_v);
  const int periods = static_cast<int>(kDuration / kDt);
  SolverStats total;
  double simulated = 0.0;
  for (auto _ : state) {
    plant.reset();
    for (int k = 0; k < periods; ++k) {
      const double u = signalValue(sig, k * kDt);
      for (int j = 0; j < n; ++j) cmd.command[j] = u;
      if (!plant.step(kDt, cmd).ok()) {
        state.SkipWithError(plant.lastError());
        return;
      }
    }
    simulated += kDuration;
    const SolverStats& s = plant.stats();
    total.steps += s.steps;
    total.jac_evals += s.jac_evals;
    total.rhs_evals += s.rhs_evals;
    total.reinits += s.reinits;
    total.root_events += s.root_events;
    total.err_test_fails += s.err_test_fails;
  }
  state.counters["rtf"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
  state.counters["steps_per_sim_s"] = static_cast<double>(total.steps) / simulated;
  state.counters["jacs_per_sim_s"] = static_cast<double>(total.jac_evals) / simulated;
  state.counters["rhs_per_sim_s"] = static_cast<double>(total.rhs_evals) / simulated;
  state.counters["reinits_per_sim_s"] = static_cast<double>(total.reinits) / simulated;
  state.counters["events_per_sim_s"] = static_cast<double>(total.root_events) / simulated;
  state.counters["rejects_per_sim_s"] = static_cast<double>(total.err_test_fails) / simulated;
}

// CVODES (BDF, the reference integrator and the default).
void BM_Plant_Joint_Chirp(benchmark::State& state) {
  runPlant(state, false, true, IntegratorKind::kCvodes);
}
void BM_Plant_Joint_SlowSine(benchmark::State& state) {
  runPlant(state, false, false, IntegratorKind::kCvodes);
}
void BM_Plant_Arm_Chirp(benchmark::State& state) {
  runPlant(state, true, true, IntegratorKind::kCvodes);
}
void BM_Plant_Arm_SlowSine(benchmark::State& state) {
  runPlant(state, true, false, IntegratorKind::kCvodes);
}
BENCHMARK(BM_Plant_Joint_Chirp)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Joint_SlowSine)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_Chirp)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_SlowSine)->Unit(benchmark::kMillisecond);

// Rodas3 (one-step Rosenbrock, `solver.integrator: rodas3`), same scenarios.
void BM_Plant_Joint_Chirp_Rodas3(benchmark::State& state) {
  runPlant(state, false, true, IntegratorKind::kRodas3);
}
void BM_Plant_Joint_SlowSine_Rodas3(benchmark::State& state) {
  runPlant(state, false, false, IntegratorKind::kRodas3);
}
void BM_Plant_Arm_Chirp_Rodas3(benchmark::State& state) {
  runPlant(state, true, true, IntegratorKind::kRodas3);
}
void BM_Plant_Arm_SlowSine_Rodas3(benchmark::State& state) {
  runPlant(state, true, false, IntegratorKind::kRodas3);
}
BENCHMARK(BM_Plant_Joint_Chirp_Rodas3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Joint_SlowSine_Rodas3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_Chirp_Rodas3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_SlowSine_Rodas3)->Unit(benchmark::kMillisecond);
// Rodas3 with the opt-in rigid-body derivatives once per period (SolverOptions).
void BM_Plant_Arm_Chirp_Rodas3_RigidOncePerPeriod(benchmark::State& state) {
  runPlant(state, true, true, IntegratorKind::kRodas3, true);
}
BENCHMARK(BM_Plant_Arm_Chirp_Rodas3_RigidOncePerPeriod)->Unit(benchmark::kMillisecond);

// Rodas4 (order 4(3) Rosenbrock, `solver.integrator: rodas4`), same scenarios.
void BM_Plant_Joint_Chirp_Rodas4(benchmark::State& state) {
  runPlant(state, false, true, IntegratorKind::kRodas4);
}
void BM_Plant_Joint_SlowSine_Rodas4(benchmark::State& state) {
  runPlant(state, false, false, IntegratorKind::kRodas4);
}
void BM_Plant_Arm_Chirp_Rodas4(benchmark::State& state) {
  runPlant(state, true, true, IntegratorKind::kRodas4);
}
void BM_Plant_Arm_SlowSine_Rodas4(benchmark::State& state) {
  runPlant(state, true, false, IntegratorKind::kRodas4);
}
BENCHMARK(BM_Plant_Joint_Chirp_Rodas4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Joint_SlowSine_Rodas4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_Chirp_Rodas4)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_SlowSine_Rodas4)->Unit(benchmark::kMillisecond);

// ROS34PW2 (Rosenbrock-W, `solver.integrator: ros34pw2`: Jacobian once per period), same scenarios.
void BM_Plant_Joint_Chirp_Ros34pw2(benchmark::State& state) {
  runPlant(state, false, true, IntegratorKind::kRos34pw2);
}
void BM_Plant_Joint_SlowSine_Ros34pw2(benchmark::State& state) {
  runPlant(state, false, false, IntegratorKind::kRos34pw2);
}
void BM_Plant_Arm_Chirp_Ros34pw2(benchmark::State& state) {
  runPlant(state, true, true, IntegratorKind::kRos34pw2);
}
void BM_Plant_Arm_SlowSine_Ros34pw2(benchmark::State& state) {
  runPlant(state, true, false, IntegratorKind::kRos34pw2);
}
BENCHMARK(BM_Plant_Joint_Chirp_Ros34pw2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Joint_SlowSine_Ros34pw2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_Chirp_Ros34pw2)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Plant_Arm_SlowSine_Ros34pw2)->Unit(benchmark::kMillisecond);

// Peer: fixed-step RK4 of the same right-hand side (one joint, 10 us step).
void BM_Peer_Rk4_Joint_Chirp(benchmark::State& state) {
  ArmPlant plant;
  const JointParams joint = config().joints[static_cast<std::size_t>(findPlantJoint(config(), "EB"))];
  plant.configure(model(), {joint}, model().defaultPosture(), UserArmParams{}, config().solver, config().seed);
  const SignalParams sig = signal(true, 1.0 / joint.valve.amplifier_gain_per_v);
  PlantCommand cmd = PlantCommand::zero(1);
  constexpr double h = 1e-5;
  const int periods = static_cast<int>(kDuration / kDt);
  double simulated = 0.0;
  for (auto _ : state) {
    plant.reset();
    Eigen::Matrix<double, 6, 1> y = plant.stateVector();
    Eigen::Matrix<double, 6, 1> k1, k2, k3, k4, tmp;
    for (int k = 0; k < periods; ++k) {
      cmd.command[0] = signalValue(sig, k * kDt);
      plant.setCommand(cmd);
      for (int i = 0; i < static_cast<int>(kDt / h + 0.5); ++i) {
        plant.evaluateRhs(y.data(), k1.data());
        tmp = y + 0.5 * h * k1;
        plant.evaluateRhs(tmp.data(), k2.data());
        tmp = y + 0.5 * h * k2;
        plant.evaluateRhs(tmp.data(), k3.data());
        tmp = y + h * k3;
        plant.evaluateRhs(tmp.data(), k4.data());
        y += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
      }
    }
    benchmark::DoNotOptimize(y.data());
    simulated += kDuration;
  }
  state.counters["rtf"] = benchmark::Counter(simulated, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Peer_Rk4_Joint_Chirp)->Unit(benchmark::kMillisecond);

// The rigid-body derivatives d ID/d(q, qd) of the 7-joint reduced arm (one call per Rodas3 Jacobian): the composite
// form (R13, what the plant uses) and, in the same run, the body-by-body form (R6-R8) it replaced.
void runRigidDerivatives(benchmark::State& state, bool composite) {
  std::vector<int> active;
  for (const JointParams& j : config().joints) active.push_back(model().jointIndex(j.name));
  const arm::RigidBodyModel reduced = arm::reduceArmModel(model(), active, model().defaultPosture());
  const int n = reduced.tree.n;
  arm::RigidBodyData data;
  arm::BodyVector q = arm::BodyVector::LinSpaced(n, -0.4, 0.5);
  const arm::BodyVector qd = arm::BodyVector::LinSpaced(n, 1.0, -0.8);
  const arm::BodyVector qdd = arm::BodyVector::LinSpaced(n, -3.0, 2.0);
  arm::BodyVector tau(n);
  arm::BodyMatrix dq(n, n);
  arm::BodyMatrix dqd(n, n);
  arm::computeRigidBodyKinematics(reduced, data, q, qd);
  for (auto _ : state) {
    if (composite) {
      arm::computeRigidBodyInverseDynamicsDerivatives(reduced.tree, data, qdd, tau, dq, dqd);
    } else {
      arm::computeRigidBodyInverseDynamicsDerivativesPerBody(reduced.tree, data, qdd, tau, dq, dqd);
    }
    benchmark::DoNotOptimize(dq.data());
    benchmark::DoNotOptimize(dqd.data());
    benchmark::ClobberMemory();
  }
}
void BM_RigidDerivatives_Composite(benchmark::State& state) {
  runRigidDerivatives(state, true);
}
void BM_RigidDerivatives_PerBody(benchmark::State& state) {
  runRigidDerivatives(state, false);
}
BENCHMARK(BM_RigidDerivatives_Composite);
BENCHMARK(BM_RigidDerivatives_PerBody);

}  // namespace

BENCHMARK_MAIN();
