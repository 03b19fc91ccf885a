// The whole-arm plant against fullarm::arm (independent Newton-Euler inverse dynamics and
// energy conservation), the analytic Jacobian against finite differences, solver statistics.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "matrix_compare.hpp"
#include "plant_fixture.hpp"
#include "plant_test_util.hpp"

namespace fullarm::plant {
namespace {

using test::PlantTolerance;

std::vector<JointParams> idealJoints(const arm::ArmModel& model) {
  std::vector<JointParams> joints;
  for (int i = 0; i < model.numArmJoints(); ++i) {
    JointParams p;
    p.name = model.joints[static_cast<std::size_t>(i)].name;
    p.actuator.kind = ActuatorKind::kIdealTorque;
    p.actuator.inertia_kgm2 = 0.0;
    p.min_rad = model.joints[static_cast<std::size_t>(i)].limits.min_rad;
    p.max_rad = model.joints[static_cast<std::size_t>(i)].limits.max_rad;
    p.potentiometer = model.joints[static_cast<std::size_t>(i)].potentiometer;
    p.torque_sensor = model.joints[static_cast<std::size_t>(i)].torque_sensor;
    joints.push_back(p);
  }
  return joints;
}

// The seven arm joints at the default posture, swinging at 0.3 rad/s in alternating directions.
std::vector<JointState> swingingStart(const arm::ArmModel& model) {
  std::vector<JointState> s(7);
  for (int k = 0; k < 7; ++k) {
    s[static_cast<std::size_t>(k)].q_rad = model.defaultPosture()[k];
    s[static_cast<std::size_t>(k)].qd_radps = 0.3 * (k % 2 == 0 ? 1.0 : -1.0);
  }
  return s;
}

// With ideal torque sources, the plant's accelerations satisfy fullarm::arm's inverse
// dynamics: ID(q, qd, qdd_plant) = tau_command (hand joints locked at their posture).
TEST(ArmPlant, IdealTorqueSourcesReproduceRigidBodyDynamics) {
  const arm::ArmModel& model = test::dtsModel();
  ArmPlant plant;
  plant.configure(model, idealJoints(model), model.defaultPosture(), UserArmParams{}, SolverOptions{});
  const int n = plant.numJoints();
  ASSERT_EQ(n, 7);
  arm::ArmData data(model);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd y = Eigen::VectorXd::Zero(6 * n);
    PlantCommand cmd = PlantCommand::zero(n);
    Eigen::VectorXd q = model.defaultPosture();
    Eigen::VectorXd qd = Eigen::VectorXd::Zero(model.numJoints());
    for (int k = 0; k < n; ++k) {
      const arm::JointLimits& lim = model.joints[static_cast<std::size_t>(k)].limits;
      q[k] = lim.min_rad + 0.5 * (unit(rng) + 1.0) * (lim.max_rad - lim.min_rad);
      qd[k] = 2.0 * unit(rng);
      cmd.command[k] = 20.0 * unit(rng);
      y[4 * n + k] = q[k];
      y[5 * n + k] = qd[k];
    }
    plant.setCommand(cmd);
    Eigen::VectorXd ydot(6 * n);
    plant.evaluateRhs(y.data(), ydot.data());
    Eigen::VectorXd qdd = Eigen::VectorXd::Zero(model.numJoints());
    qdd.head(n) = ydot.segment(5 * n, n);
    arm::computeInverseDynamics(model, data, q, qd, qdd);
    const Eigen::VectorXd tau = data.tau.head(n);
    const Eigen::VectorXd expected = cmd.command.head(n);
    EXPECT_MATRIX_NEAR(tau, expected, PlantTolerance::kRigidBody * std::max(1.0, expected.norm()));
    EXPECT_MATRIX_NEAR(ydot.segment(4 * n, n), qd.head(n), 0.0);
  }
}

// Zero command, no friction: kinetic + potential energy of fullarm::arm is conserved along the
// integrated trajectory.
TEST(ArmPlant, IdealTorqueFreeMotionConservesArmEnergy) {
  const arm::ArmModel& model = test::dtsModel();
  SolverOptions o;
  o.rtol = 1e-10;
  o.atol_angle_rad = 1e-12;
  o.atol_velocity_radps = 1e-10;
  ArmPlant plant;
  plant.configure(model, idealJoints(model), model.defaultPosture(), UserArmParams{}, o);
  plant.reset(swingingStart(model));
  arm::ArmData data(model);
  auto energy = [&] {
    Eigen::VectorXd q = model.defaultPosture();
    Eigen::VectorXd qd = Eigen::VectorXd::Zero(model.numJoints());
    for (int k = 0; k < 7; ++k) {
      q[k] = plant.state(k).q_rad;
      qd[k] = plant.state(k).qd_radps;
    }
    return arm::computeKineticEnergy(model, data, q, qd) + arm::computePotentialEnergy(model, data, q);
  };
  const double e0 = energy();
  double ke_scale = 0.0;
  const PlantCommand cmd = PlantCommand::zero(7);
  for (int k = 0; k < 300; ++k) {
    ASSERT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
    ke_scale = std::max(ke_scale, std::abs(energy() - e0));
  }
  Eigen::VectorXd q0 = model.defaultPosture();
  const double ke0 = e0 - arm::computePotentialEnergy(model, data, q0);
  EXPECT_LE(ke_scale, PlantTolerance::kRigidBody * std::abs(e0) + 1e-6 * ke0);
  EXPECT_GT(plant.stats().steps, 0);
}

// The analytic Jacobian of a single joint (every term included) equals central differences of
// the right-hand side; cylinder, entrained air, leakage, friction, torque loop.
TEST(ArmPlant, AnalyticJacobianMatchesFiniteDifferences) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  for (const InputMode mode : {InputMode::kValveVoltage, InputMode::kTorqueLoop}) {
    JointParams p = config.joints[static_cast<std::size_t>(findPlantJoint(config, "EB"))];
    p.input_mode = mode;
    p.torque_loop.gain_v_per_nm = 0.05;
    p.chambers.external_leakage_m3ps_per_pa = 1e-14;
    UserArmParams user = config.user_arm;
    user.enabled = true;
    ArmPlant plant;
    plant.configure(model, {p}, model.defaultPosture(), user, SolverOptions{});
    Eigen::VectorXd y(6);
    y << 0.3, 40.0, 12.0e6, 8.0e6, 1.2, 0.7;
    PlantCommand cmd = PlantCommand::zero(1);
    cmd.command[0] = 2.0;
    cmd.tau_user_nm[0] = 1.0;
    plant.setCommand(cmd);
    Eigen::MatrixXd J(6, 6);
    plant.evaluateJacobian(y.data(), J.data());
    Eigen::MatrixXd fd(6, 6);
    Eigen::VectorXd fp(6), fm(6);
    const Eigen::VectorXd scale = (Eigen::VectorXd(6) << 1e-2, 1.0, 1e5, 1e5, 1e-2, 1e-1).finished();
    for (int c = 0; c < 6; ++c) {
      const double h = 1e-5 * scale[c];
      Eigen::VectorXd yp = y, ym = y;
      yp[c] += h;
      ym[c] -= h;
      plant.evaluateRhs(yp.data(), fp.data());
      plant.evaluateRhs(ym.data(), fm.data());
      fd.col(c) = (fp - fm) / (2.0 * h);
    }
    for (int r = 0; r < 6; ++r) {
      for (int c = 0; c < 6; ++c) {
        EXPECT_NEAR(J(r, c), fd(r, c), 1e-5 * (std::abs(fd(r, c)) + fd.row(r).cwiseAbs().maxCoeff() * 1e-3) + 1e-9)
            << "row " << r << " col " << c << " mode " << static_cast<int>(mode);
      }
    }
  }
}

// Solver statistics are exposed and accumulate across re-initialisations.
TEST(ArmPlant, StatisticsAccumulateAcrossReinit) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  ArmPlant plant;
  plant.configure(model, {config.joints[3]}, model.defaultPosture(), UserArmParams{}, config.solver);
  PlantCommand cmd = PlantCommand::zero(1);
  long previous_steps = 0;
  for (int k = 0; k < 50; ++k) {
    cmd.command[0] = (k / 10) % 2 == 0 ? 3.0 : -3.0;  // jumps of 60 % of full scale: re-init
    ASSERT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
    EXPECT_GE(plant.stats().steps, previous_steps);
    previous_steps = plant.stats().steps;
  }
  EXPECT_GE(plant.stats().reinits, 5);
  EXPECT_GT(plant.stats().jac_evals, 0);
  EXPECT_GT(plant.stats().rhs_evals, plant.stats().steps);
}

// reset() starts the counters from zero: a second identical run reports what the first did
// (CVODES keeps its own counters until the next CVodeReInit, which used to bank the previous
// run's last segment into the new run's statistics: twice the steps of a slow sine).
TEST(ArmPlant, StatisticsRestartAtReset) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  ArmPlant plant;
  plant.configure(model, {config.joints[3]}, model.defaultPosture(), UserArmParams{}, config.solver);
  auto run = [&plant]() {
    plant.reset();
    PlantCommand cmd = PlantCommand::zero(1);
    for (int k = 0; k < 200; ++k) {
      cmd.command[0] = 0.5 * std::sin(2.0 * std::numbers::pi * 2.0 * k * 1e-3);  // no re-init
      EXPECT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
    }
    return plant.stats();
  };
  const SolverStats first = run();
  const SolverStats second = run();
  EXPECT_GT(first.steps, 0);
  EXPECT_EQ(first.reinits, 1);
  EXPECT_EQ(second.steps, first.steps);
  EXPECT_EQ(second.rhs_evals, first.rhs_evals);
  EXPECT_EQ(second.jac_evals, first.jac_evals);
  EXPECT_EQ(second.reinits, first.reinits);
}

// Rodas3 on pure rigid-body motion (ideal torque sources, free swing from a spinning start):
// its Newton matrix omits the configuration gradients of M, C and g, which costs a Rosenbrock
// method its order, so it is checked at the default tolerances against CVODES at rtol 1e-10:
// the angles agree to 1e-4 rad over 1 s (CVODES at the default tolerances: see the printout).
TEST(ArmPlant, Rodas3FollowsTightCvodesOnIdealTorqueFreeMotion) {
  const arm::ArmModel& model = test::dtsModel();
  auto run = [&](const SolverOptions& o) {
    ArmPlant plant;
    plant.configure(model, idealJoints(model), model.defaultPosture(), UserArmParams{}, o);
    plant.reset(swingingStart(model));
    const PlantCommand cmd = PlantCommand::zero(7);
    for (int k = 0; k < 1000; ++k) EXPECT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
    Eigen::VectorXd q(7);
    for (int k = 0; k < 7; ++k) q[k] = plant.state(k).q_rad;
    return q;
  };
  SolverOptions tight;
  tight.rtol = 1e-10;
  tight.atol_angle_rad = 1e-12;
  tight.atol_velocity_radps = 1e-10;
  const Eigen::VectorXd ref = run(tight);
  SolverOptions rodas = test::dtsPlant().solver;
  rodas.integrator = IntegratorKind::kRodas3;
  const Eigen::VectorXd q_rodas = run(rodas);
  rodas.integrator = IntegratorKind::kRodas4;
  const Eigen::VectorXd q_rodas4 = run(rodas);
  // The opt-in reuse of the rigid-body derivatives within a period (the block is all of the
  // Jacobian here: dropping it entirely puts Rodas3 1.6 rad off after 1 s).
  rodas.integrator = IntegratorKind::kRodas3;
  rodas.rigid_derivatives_once_per_period = true;
  const Eigen::VectorXd q_once = run(rodas);
  const Eigen::VectorXd q_cvodes = run(test::dtsPlant().solver);
  std::printf(
      "ideal-torque free motion, max |q - q_ref| after 1 s: Rodas3 %.2e rad, Rodas4 %.2e rad, Rodas3 with the "
      "rigid-body derivatives once per period %.2e rad, CVODES %.2e rad\n",
      (q_rodas - ref).cwiseAbs().maxCoeff(), (q_rodas4 - ref).cwiseAbs().maxCoeff(),
      (q_once - ref).cwiseAbs().maxCoeff(), (q_cvodes - ref).cwiseAbs().maxCoeff());
  EXPECT_LT((q_rodas - ref).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_LT((q_rodas4 - ref).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_LT((q_once - ref).cwiseAbs().maxCoeff(), 1e-4);
  EXPECT_GT((ref - model.defaultPosture().head(7)).cwiseAbs().maxCoeff(), 0.05);  // it moved
}

// With the rigid-body derivatives reused within a period, Rodas3's Jacobians after a period's
// first one are stale by design, but the public evaluateJacobian() must stay exact: equal, entry
// for entry, to that of a plant without the reuse, at states other than the period's start.
TEST(ArmPlant, PublicJacobianStaysExactWithRigidDerivativesOncePerPeriod) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  SolverOptions options = config.solver;
  options.integrator = IntegratorKind::kRodas3;
  ArmPlant exact;
  exact.configure(model, config.joints, model.defaultPosture(), UserArmParams{}, options, 1);
  options.rigid_derivatives_once_per_period = true;
  ArmPlant reusing;
  reusing.configure(model, config.joints, model.defaultPosture(), UserArmParams{}, options, 1);
  const int n = reusing.numJoints();
  PlantCommand cmd = PlantCommand::zero(n);
  for (int j = 0; j < n; ++j) cmd.command[j] = 3.0 * std::sin(j + 1.0);
  for (int k = 0; k < 50; ++k) ASSERT_TRUE(reusing.step(1e-3, cmd).ok());
  EXPECT_GT(reusing.stats().steps, 50);  // several Jacobians per period: the reuse was exercised
  exact.setCommand(cmd);
  const Eigen::VectorXd y = reusing.stateVector();
  const int N = static_cast<int>(y.size());
  for (int trial = 0; trial < 2; ++trial) {
    Eigen::VectorXd yt = y;
    for (int j = 0; j < n; ++j) {
      yt[4 * n + j] += 0.05 * (trial + 1) * std::cos(j + 2.0);  // q
      yt[5 * n + j] += 0.5 * (trial + 1) * std::sin(j + 3.0);   // qd
    }
    Eigen::MatrixXd ja(N, N), jb(N, N);
    exact.evaluateJacobian(yt.data(), ja.data());
    reusing.evaluateJacobian(yt.data(), jb.data());
    EXPECT_EQ((ja - jb).cwiseAbs().maxCoeff(), 0.0) << "trial " << trial;
  }
}

}  // namespace
}  // namespace fullarm::plant
