// The joint controllers against independent results: the analytic step response of
// J s^2 + B s + K, a fine RK4 integration of the continuous Eq. (8), the analytic first-order
// filter response, hand-computed PID and passivity-observer sums; sign conventions; saturation;
// fault injection; allocation-free stepping.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "alloc_guard.hpp"
#include "controllers_fixture.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/controllers/arm_controller.hpp"
#include "fullarm/controllers/joint_controller.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::controllers {
namespace {

struct Tolerance {
  static constexpr double kExactZoh = 1e-9;       // relative: ZOH of a step is exact
  static constexpr double kEq8Continuous = 0.01;  // relative to the peak command, T = 0.1 ms
  static constexpr double kRoundoff = 1e-12;
};

JointGains baseGains() {
  JointGains g;
  g.name = "R_EB";
  g.impedance = {0.05, 1.0, 50.0};
  g.sliding_mode = {30.0, 5.0, 0.7};
  g.torque_pid = {0.2, 0.0, 0.0, 2.0};
  g.valve_limit_v = 10.0;
  return g;
}

JointInput userTorque(double q, double tau_user) {
  // A joint at rest with exact gravity model: the load cell reads g - tau_user (g = 0 here).
  JointInput in;
  in.q_rad = q;
  in.tau_load_cell_nm = -tau_user;
  return in;
}

// Analytic unit-step response of 1 / (J s^2 + B s + K) from rest.
double analyticStep(double J, double B, double K, double t) {
  const double wn = std::sqrt(K / J);
  const double zeta = B / (2.0 * std::sqrt(K * J));
  if (zeta < 1.0) {
    const double wd = wn * std::sqrt(1.0 - zeta * zeta);
    return (1.0 - std::exp(-zeta * wn * t) * (std::cos(wd * t) + zeta * wn / wd * std::sin(wd * t))) / K;
  }
  if (zeta > 1.0) {
    const double r = wn * std::sqrt(zeta * zeta - 1.0);
    const double p1 = -zeta * wn + r;
    const double p2 = -zeta * wn - r;
    return (1.0 + (p2 * std::exp(p1 * t) - p1 * std::exp(p2 * t)) / (p1 - p2)) / K;
  }
  return (1.0 - std::exp(-wn * t) * (1.0 + wn * t)) / K;
}

TEST(ImpedanceModel, DiscreteIntegratorMatchesAnalyticStepResponse) {
  // Underdamped, critically damped and overdamped models; theta_d = q = 0 held.
  for (const ImpedanceParams imp :
       {ImpedanceParams{0.05, 1.0, 50.0}, ImpedanceParams{0.02, 2.0 * std::sqrt(0.02 * 8.0), 8.0},
        ImpedanceParams{0.01, 3.0, 20.0}}) {
    JointGains g = baseGains();
    g.impedance = imp;
    const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kAdmittance, 1e-3);
    JointControllerData d;
    resetJointController(m, d, 0.0);
    const double tau = 2.5;
    double worst = 0.0;
    for (int k = 1; k <= 2000; ++k) {
      (void)stepJointController(m, d, userTorque(0.0, tau));
      const double expected =
          tau * analyticStep(imp.inertia_kgm2, imp.damping_nms_per_rad, imp.stiffness_nm_per_rad, k * 1e-3);
      worst = std::max(worst, std::abs(d.theta_m_rad - expected));
      // With theta_d = q = 0 the error of Eq. (5) is the model angle.
      EXPECT_EQ(d.error_rad, d.theta_m_rad);
    }
    EXPECT_LT(worst, Tolerance::kExactZoh * tau / imp.stiffness_nm_per_rad) << "J=" << imp.inertia_kgm2;
    // Steady state of Eq. (5): theta_error = tau / K_m.
    EXPECT_NEAR(d.error_rad, tau / imp.stiffness_nm_per_rad, 1e-6);
  }
}

// Eq. (8): in the continuous region the admittance controller is
// u = (B_o/eps)(s + lambda)[(tau + K_m theta_d)/(J_m s^2 + B_m s + K_m) - theta_d].
// Reference: RK4 of the continuous impedance model on a 100x finer grid, exact derivatives.
TEST(AdmittanceController, MatchesContinuousEq8InTheLinearRegion) {
  JointGains g = baseGains();
  g.sliding_mode.boundary_layer_radps = 20.0;  // keep sat() linear (checked below)
  const double T = 1e-4;
  const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kAdmittance, T);
  const double J = g.impedance.inertia_kgm2, B = g.impedance.damping_nms_per_rad, K = g.impedance.stiffness_nm_per_rad;
  const double k_gain = g.sliding_mode.valve_bound_v / g.sliding_mode.boundary_layer_radps;
  const double lambda = g.sliding_mode.lambda_per_s;
  auto tau_of = [](double t) { return 1.5 * std::sin(2.0 * std::numbers::pi * 1.3 * t) + 0.5; };
  auto q_of = [](double t) { return 0.2 * std::sin(2.0 * std::numbers::pi * 0.7 * t); };
  auto qd_of = [](double t) { return 0.2 * 2.0 * std::numbers::pi * 0.7 * std::cos(2.0 * std::numbers::pi * 0.7 * t); };

  JointControllerData d;
  resetJointController(m, d, q_of(0.0));
  // Continuous reference state, started like the controller (model at the arm, at rest).
  double th = q_of(0.0), om = 0.0, t = 0.0;
  auto f = [&](double tt, double x, double v, double& dx, double& dv) {
    dx = v;
    dv = (tau_of(tt) + K * q_of(tt) - B * v - K * x) / J;
  };
  double worst = 0.0, peak = 0.0;
  const int sub = 100;
  for (int k = 0; k < 30000; ++k) {
    const double tk = k * T;
    const double v = stepJointController(m, d, userTorque(q_of(tk), tau_of(tk)));
    // Integrate the reference over the same period.
    const double h = T / sub;
    for (int i = 0; i < sub; ++i) {
      double k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v;
      f(t, th, om, k1x, k1v);
      f(t + h / 2, th + h / 2 * k1x, om + h / 2 * k1v, k2x, k2v);
      f(t + h / 2, th + h / 2 * k2x, om + h / 2 * k2v, k3x, k3v);
      f(t + h, th + h * k3x, om + h * k3v, k4x, k4v);
      th += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
      om += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
      t += h;
    }
    if (k < 5000) continue;  // after the start-up transient of the derivative
    // Continuous Eq. (8) at the same instant: e = theta_m - theta_d, e' = omega_m - theta_d'.
    const double e = th - q_of(t);
    const double u_ref = k_gain * ((om - qd_of(t)) + lambda * e);
    ASSERT_FALSE(d.saturated);
    worst = std::max(worst, std::abs(v - u_ref));
    peak = std::max(peak, std::abs(u_ref));
  }
  ASSERT_GT(peak, 0.1);
  EXPECT_LT(worst, Tolerance::kEq8Continuous * peak) << "worst " << worst << " peak " << peak;
}

TEST(AdmittanceController, SaturatesAtTheValveBound) {
  JointGains g = baseGains();
  const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kAdmittance, 1e-3);
  JointControllerData d;
  resetJointController(m, d, 0.0);
  double v = 0.0;
  for (int k = 0; k < 200; ++k) v = stepJointController(m, d, userTorque(0.0, 40.0));
  EXPECT_TRUE(d.saturated);
  EXPECT_DOUBLE_EQ(v, g.sliding_mode.valve_bound_v);  // u = B_o sat(.) never exceeds B_o
  resetJointController(m, d, 0.0);
  for (int k = 0; k < 200; ++k) v = stepJointController(m, d, userTorque(0.0, -40.0));
  EXPECT_DOUBLE_EQ(v, -g.sliding_mode.valve_bound_v);
  // In the linear region the output is exactly (B_o/eps) s.
  resetJointController(m, d, 0.0);
  v = stepJointController(m, d, userTorque(0.0, 1e-3));
  v = stepJointController(m, d, userTorque(0.0, 1e-3));
  EXPECT_FALSE(d.saturated);
  EXPECT_NEAR(v, g.sliding_mode.valve_bound_v / g.sliding_mode.boundary_layer_radps * d.surface_radps,
              Tolerance::kRoundoff);
}

// Eq. (4) signs with the plant/arm/haptics conventions of joint_controller.hpp.
TEST(TorqueAssembly, SignConventions) {
  EXPECT_DOUBLE_EQ(assembleModelTorque(3.0, 1.0, 0.5), 1.5);  // (tau_u + tau_ga) - (tau_c + tau_ge)
  const double g = 7.0, tau_user = 2.0, tau_env = -0.5;
  JointInput in;
  in.tau_gravity_nm = g;
  in.tau_contact_nm = tau_env;
  in.tau_load_cell_nm = g - tau_user;  // a link at rest: load cell = g - tau_user (plant convention)
  const PaperTorques p = paperTorques(in);
  EXPECT_DOUBLE_EQ(p.tau_measured_nm, tau_user - g);  // tau_u + tau_ga, gravity pulls toward -g
  EXPECT_DOUBLE_EQ(p.tau_gravity_expected_nm, -g);
  EXPECT_DOUBLE_EQ(p.tau_c_nm, -tau_env);  // the arm pushes into the wall
  // Gravity cancels; the model feels the user and the environment.
  EXPECT_DOUBLE_EQ(assembleModelTorque(p.tau_measured_nm, p.tau_c_nm, p.tau_gravity_expected_nm),
                   tau_user + tau_env);
  // The controller: a user pushing toward +q gives a command toward +q, a wall pushing back
  // more than the user reverses it, for both control laws.
  for (ControllerKind kind : {ControllerKind::kAdmittance, ControllerKind::kTorquePid}) {
    const JointControllerModel m = makeJointControllerModel(baseGains(), kind, 1e-3);
    JointControllerData d;
    resetJointController(m, d, 0.3);
    double v = 0.0;
    in = JointInput{0.3, g - tau_user, 0.0, g};
    for (int k = 0; k < 5; ++k) v = stepJointController(m, d, in);
    EXPECT_GT(v, 0.0);
    EXPECT_NEAR(d.tau_model_nm, tau_user, 1e-12);
    resetJointController(m, d, 0.3);
    in = JointInput{0.3, g - tau_user, -3.0, g};
    for (int k = 0; k < 5; ++k) v = stepJointController(m, d, in);
    EXPECT_LT(v, 0.0);
  }
}

TEST(TorquePid, MatchesHandComputedLaw) {
  JointGains g = baseGains();
  g.torque_pid = {0.3, 2.0, 0.004, 0.05};
  const double T = 1e-3;
  const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kTorquePid, T);
  JointControllerData d;
  resetJointController(m, d, 0.0);
  double integral = 0.0, prev = 0.0;
  for (int k = 0; k < 100; ++k) {
    const double tau = 5.0 * std::sin(0.1 * k) + 1.0;
    const double v = stepJointController(m, d, userTorque(0.0, tau));
    integral = std::clamp(integral + 2.0 * T * tau, -0.05, 0.05);
    const double deriv = k == 0 ? 0.0 : (tau - prev) / T;
    prev = tau;
    const double expected = std::clamp(0.3 * tau + integral + 0.004 * deriv, -10.0, 10.0);
    ASSERT_NEAR(v, expected, 1e-12) << k;
  }
}

TEST(TorqueFilter, MatchesFirstOrderStepResponse) {
  JointGains g = baseGains();
  g.torque_filter_hz = 20.0;
  const double T = 1e-3;
  const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kTorquePid, T);
  JointControllerData d;
  resetJointController(m, d, 0.0);
  (void)stepJointController(m, d, userTorque(0.0, 0.0));  // filter starts at 0
  for (int k = 1; k <= 100; ++k) {
    (void)stepJointController(m, d, userTorque(0.0, 1.0));
    // Sampled first-order step response 1 - exp(-2 pi f t), t = k T.
    EXPECT_NEAR(d.tau_filtered_nm, 1.0 - std::exp(-2.0 * std::numbers::pi * 20.0 * k * T), 1e-12) << k;
  }
}

// Passivity observer: E[k] = T sum tau_user_est qdot, by hand; controller: alpha and E >= 0.
TEST(PassivityObserver, EnergyMatchesHandComputedSums) {
  JointGains g = baseGains();
  const double T = 1e-3;
  for (bool enabled : {false, true}) {
    g.passivity.enabled = enabled;
    g.passivity.max_damping_nms_per_rad = 1e6;
    g.passivity.velocity_threshold_radps = 0.0;
    const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kAdmittance, T);
    JointControllerData d;
    resetJointController(m, d, 0.0);
    double energy = 0.0, dissipated = 0.0, q_prev = 0.0;
    for (int k = 0; k < 400; ++k) {
      // The user's torque and the arm's motion out of phase half of the time: energy flows out.
      const double q = 0.1 * std::sin(0.05 * k);
      const double tau_user = 2.0 * std::cos(0.05 * k + 2.0);
      (void)stepJointController(m, d, userTorque(q, tau_user));
      const double qdot = k == 0 ? 0.0 : (q - q_prev) / T;
      q_prev = q;
      energy += T * tau_user * qdot;
      double alpha = 0.0;
      if (enabled && energy < 0.0 && qdot != 0.0) alpha = -energy / (T * qdot * qdot);
      energy += T * alpha * qdot * qdot;
      dissipated += T * alpha * qdot * qdot;
      ASSERT_NEAR(d.po_energy_j, energy, 1e-12) << k;
      ASSERT_NEAR(d.po_damping_nms_per_rad, alpha, 1e-9 * std::max(1.0, alpha)) << k;
      ASSERT_NEAR(d.po_dissipated_j, dissipated, 1e-12) << k;
      if (enabled) {
        EXPECT_GE(d.po_energy_j, -1e-12) << k;  // the controller restores passivity each step
        EXPECT_NEAR(d.tau_model_nm, tau_user - alpha * qdot, 1e-9) << k;
      }
    }
    if (enabled) {
      EXPECT_GT(dissipated, 0.0);
    } else {
      EXPECT_LT(energy, 0.0);  // the scenario does generate energy at the port
    }
  }
}

TEST(PassivityController, DampingIsCapped) {
  JointGains g = baseGains();
  g.passivity.enabled = true;
  g.passivity.max_damping_nms_per_rad = 0.5;
  const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kAdmittance, 1e-3);
  JointControllerData d;
  resetJointController(m, d, 0.0);
  double q = 0.0;
  for (int k = 0; k < 100; ++k) {
    q += 1e-3;  // moving toward +q while the user pulls toward -q: energy out of the device
    (void)stepJointController(m, d, userTorque(q, -3.0));
    EXPECT_LE(d.po_damping_nms_per_rad, 0.5);
  }
  EXPECT_DOUBLE_EQ(d.po_damping_nms_per_rad, 0.5);
  EXPECT_LT(d.po_energy_j, 0.0);  // the capped controller cannot absorb it all
}

// Fault injection: every non-finite input gives exactly 0 V and a latched fault bit.
TEST(JointControllerSafety, NonFiniteInputsGiveSafeOutput) {
  const double bad_values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(),
                               -std::numeric_limits<double>::infinity()};
  for (ControllerKind kind : {ControllerKind::kAdmittance, ControllerKind::kTorquePid}) {
    const JointControllerModel m = makeJointControllerModel(baseGains(), kind, 1e-3);
    for (int field = 0; field < 4; ++field) {
      for (double bad : bad_values) {
        JointControllerData d;
        resetJointController(m, d, 0.0);
        for (int k = 0; k < 20; ++k) (void)stepJointController(m, d, userTorque(0.0, 30.0));
        ASSERT_NE(d.valve_command_v, 0.0);
        JointInput in = userTorque(0.0, 30.0);
        double* fields[] = {&in.q_rad, &in.tau_load_cell_nm, &in.tau_contact_nm, &in.tau_gravity_nm};
        *fields[field] = bad;
        EXPECT_EQ(stepJointController(m, d, in), 0.0);
        EXPECT_TRUE(d.status.has(kFaultNonFiniteInput));
        // Latched: good inputs do not restart the valve.
        EXPECT_EQ(stepJointController(m, d, userTorque(0.0, 30.0)), 0.0);
        EXPECT_EQ(d.valve_command_v, 0.0);
        resetJointController(m, d, 0.0);
        EXPECT_TRUE(d.status.ok());
        EXPECT_NE(stepJointController(m, d, userTorque(0.0, 30.0)), 0.0);
      }
    }
  }
  // Stepping without reset is a fault too.
  const JointControllerModel m = makeJointControllerModel(baseGains(), ControllerKind::kAdmittance, 1e-3);
  JointControllerData fresh;
  EXPECT_EQ(stepJointController(m, fresh, userTorque(0.0, 30.0)), 0.0);
  EXPECT_TRUE(fresh.status.has(kFaultNotConfigured));
}

TEST(JointControllerSafety, OverflowingStateGivesSafeOutput) {
  // Finite but absurd torques overflow the PID state: caught as a state fault.
  JointGains g = baseGains();
  g.torque_pid = {1e300, 0.0, 1e300, 1.0};
  const JointControllerModel m = makeJointControllerModel(g, ControllerKind::kTorquePid, 1e-3);
  JointControllerData d;
  resetJointController(m, d, 0.0);
  (void)stepJointController(m, d, userTorque(0.0, 1e300));
  EXPECT_EQ(stepJointController(m, d, userTorque(0.0, -1e300)), 0.0);
  EXPECT_TRUE(d.status.has(kFaultNonFiniteState));
}

TEST(JointControllerSafety, OutputNeverExceedsTheValveLimit) {
  JointGains g = baseGains();
  g.valve_limit_v = 3.0;
  g.sliding_mode.valve_bound_v = 3.0;
  g.torque_pid.kp_v_per_nm = 10.0;
  for (ControllerKind kind : {ControllerKind::kAdmittance, ControllerKind::kTorquePid}) {
    const JointControllerModel m = makeJointControllerModel(g, kind, 1e-3);
    JointControllerData d;
    resetJointController(m, d, 0.0);
    for (int k = 0; k < 500; ++k) {
      const double v = stepJointController(m, d, userTorque(0.01 * std::sin(0.3 * k), 100.0 * std::sin(0.01 * k)));
      ASSERT_LE(std::abs(v), 3.0);
    }
  }
}

TEST(JointController, InvalidGainsAreRejected) {
  JointGains g = baseGains();
  g.impedance.inertia_kgm2 = -1.0;
  EXPECT_THROW((void)makeJointControllerModel(g, ControllerKind::kAdmittance, 1e-3), core::ConfigError);
  g = baseGains();
  EXPECT_THROW((void)makeJointControllerModel(g, ControllerKind::kAdmittance, 0.0), core::ConfigError);
}

TEST(ArmController, GravityFromTheArmModelCancelsAtRest) {
  const arm::ArmModel& model = test::dtsModel();
  const ArmControllerModel c = makeArmControllerModel(test::dtsGains(), model);
  ASSERT_EQ(c.numJoints(), 7);
  arm::ArmData arm_data(model);
  ArmControllerData d;
  Eigen::VectorXd q = model.defaultPosture();
  q[1] += 0.3;
  q[3] += 0.5;
  resetArmController(c, d, q);
  // The load cells read exactly g(q): the user does nothing, so every model torque is 0.
  arm::computeGravityTorques(model, arm_data, q);
  Eigen::VectorXd cells(7);
  c.selection.gather(arm_data.tau_gravity, cells);
  const Eigen::VectorXd env = Eigen::VectorXd::Zero(model.numJoints());
  Eigen::VectorXd v(7);
  stepArmController(c, d, q, arm_data.tau_gravity, env, cells, v);
  ASSERT_GT(cells.cwiseAbs().maxCoeff(), 1.0);  // gravity is not trivially zero here
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(d.joints[static_cast<std::size_t>(i)].tau_model_nm, 0.0, 1e-12) << i;
  EXPECT_NEAR(v.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  // One bad load cell stops every valve.
  for (int k = 0; k < 10; ++k)
    stepArmController(c, d, q, arm_data.tau_gravity, env, cells + Eigen::VectorXd::Constant(7, -5.0), v);
  ASSERT_GT(v.cwiseAbs().minCoeff(), 0.0);
  Eigen::VectorXd bad = cells;
  bad[4] = std::numeric_limits<double>::quiet_NaN();
  stepArmController(c, d, q, arm_data.tau_gravity, env, bad, v);
  EXPECT_EQ(v.cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(d.status.has(kFaultNonFiniteInput));
}

// The configuration vectors are read at the controlled joints' model indices and the subset
// vectors in the gains file's order: a gains file listing the joints out of model order maps
// each joint's gravity, contact torque and load cell to the right controller.
TEST(ArmController, ReadsConfigurationVectorsThroughItsSelection) {
  const arm::ArmModel& model = test::dtsModel();
  GainsConfig gains = test::dtsGains();
  std::reverse(gains.joints.begin(), gains.joints.end());
  const ArmControllerModel c = makeArmControllerModel(gains, model);
  const int n = c.numJoints();
  ArmControllerData d;
  const Eigen::VectorXd q = model.defaultPosture();
  resetArmController(c, d, q);
  Eigen::VectorXd gravity = Eigen::VectorXd::Zero(model.numJoints());
  Eigen::VectorXd env = Eigen::VectorXd::Zero(model.numJoints());
  Eigen::VectorXd cells = Eigen::VectorXd::Zero(n);
  for (int m = 0; m < model.numJoints(); ++m) {
    gravity[m] = 1.0 + m;
    env[m] = 0.25 * m;
  }
  for (int k = 0; k < n; ++k) cells[k] = 0.1 * k;
  Eigen::VectorXd v(n);
  stepArmController(c, d, q, gravity, env, cells, v);
  for (int k = 0; k < n; ++k) {
    const int m = model.jointIndex(gains.joints[static_cast<std::size_t>(k)].name);
    // Eq. (4) before the filter's first step: tau = g + tau_env - load cell, filtered from zero.
    JointControllerData reference;
    const JointControllerModel jm = c.joints[static_cast<std::size_t>(k)];
    resetJointController(jm, reference, q[m]);
    JointInput in;
    in.q_rad = q[m];
    in.tau_gravity_nm = gravity[m];
    in.tau_contact_nm = env[m];
    in.tau_load_cell_nm = cells[k];
    EXPECT_EQ(stepJointController(jm, reference, in), v[k]) << gains.joints[static_cast<std::size_t>(k)].name;
    EXPECT_EQ(reference.tau_model_nm, d.joints[static_cast<std::size_t>(k)].tau_model_nm);
  }
}

TEST(ControllersRealtime, StepsDoNotAllocate) {
  ASSERT_TRUE(testing::allocatorInterposed());
  for (ControllerKind kind : {ControllerKind::kAdmittance, ControllerKind::kTorquePid}) {
    JointGains g = baseGains();
    g.passivity.enabled = true;
    g.torque_filter_hz = 50.0;
    g.error_rate_filter_hz = 100.0;
    const JointControllerModel m = makeJointControllerModel(g, kind, 1e-3);
    JointControllerData d;
    EXPECT_NO_HEAP_ALLOCATION(resetJointController(m, d, 0.0));
    EXPECT_NO_HEAP_ALLOCATION(for (int k = 0; k < 100; ++k) {
      (void)stepJointController(m, d, userTorque(0.01 * std::sin(0.1 * k), 3.0 * std::cos(0.07 * k)));
    });
    JointInput bad = userTorque(0.0, 1.0);
    bad.q_rad = std::numeric_limits<double>::quiet_NaN();
    EXPECT_NO_HEAP_ALLOCATION((void)stepJointController(m, d, bad));
  }
  const arm::ArmModel& model = test::dtsModel();
  const ArmControllerModel c = makeArmControllerModel(test::dtsGains(), model);
  arm::ArmData arm_data(model);
  ArmControllerData d;
  const Eigen::VectorXd q = model.defaultPosture();
  arm::computeGravityTorques(model, arm_data, q);
  const Eigen::VectorXd cells = Eigen::VectorXd::Constant(7, 0.5);
  const Eigen::VectorXd env = Eigen::VectorXd::Zero(model.numJoints());
  Eigen::VectorXd v(7);
  EXPECT_NO_HEAP_ALLOCATION(resetArmController(c, d, q));
  EXPECT_NO_HEAP_ALLOCATION(
      for (int k = 0; k < 50; ++k) stepArmController(c, d, q, arm_data.tau_gravity, env, cells, v));
}

}  // namespace
}  // namespace fullarm::controllers
