// Linear analysis: margins against published vectors, ZOH discretisation against independent
// paths, the joint linearisation against finite differences of the plant's RHS, the
// controller's linear form against stepJointController(), Colgate's wall condition.

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/MatrixFunctions>

#include "design_fixture.hpp"
#include "fullarm/controllers/joint_controller.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/lti.hpp"
#include "fullarm/design/margins.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/hydraulics.hpp"
#include "matrix_compare.hpp"

namespace fullarm::design {
namespace {

using Complex = std::complex<double>;

/// Published figures are quoted to 0.5 %.
constexpr double kPublishedRelative = 0.005;
/// Colgate's boundary within 5 %.
constexpr double kColgateRelative = 0.05;

Complex polynomial(const std::vector<double>& c, Complex s) {
  Complex v = 0.0;
  for (double a : c) v = v * s + a;
  return v;
}

TEST(Margins, MatlabAllmarginVector) {
  // L = 25 / (s^3 + 10 s^2 + 10 s + 10): GM 3.6 at 3.1623 rad/s, PM 29.11 deg at 1.7844 rad/s,
  // delay margin 0.2847 s (MATLAB allmargin documentation; docs/sources.md, Control 1).
  const auto loop = [](double w) { return 25.0 / polynomial({1, 10, 10, 10}, Complex(0.0, w)); };
  const LoopMargins m = computeMargins(loop, {});
  EXPECT_NEAR(m.gain_margin, 3.6, 3.6 * kPublishedRelative);
  EXPECT_NEAR(m.gain_margin_radps, 3.1623, 3.1623 * kPublishedRelative);
  EXPECT_NEAR(m.phase_margin_deg, 29.11, 29.11 * kPublishedRelative);
  EXPECT_NEAR(m.phase_margin_radps, 1.7844, 1.7844 * kPublishedRelative);
  EXPECT_NEAR(m.delay_margin_s, 0.2847, 0.2847 * kPublishedRelative);
  // Ms against a dense brute-force scan.
  double ms = 0.0;
  for (int i = 0; i <= 200000; ++i) ms = std::max(ms, 1.0 / std::abs(1.0 + loop(1e-2 * std::pow(1e4, i / 200000.0))));
  EXPECT_NEAR(m.peak_sensitivity, ms, 1e-6 * ms);
}

TEST(Margins, IntegratorLoopVector) {
  // L = 1 / (s^3 + 2 s^2 + s): GM 2.0 at 1 rad/s, PM 21.39 deg at 0.6823 rad/s.
  const auto loop = [](double w) { return 1.0 / polynomial({1, 2, 1, 0}, Complex(0.0, w)); };
  const LoopMargins m = computeMargins(loop, {});
  EXPECT_NEAR(m.gain_margin, 2.0, 2.0 * kPublishedRelative);
  EXPECT_NEAR(m.gain_margin_radps, 1.0, kPublishedRelative);
  EXPECT_NEAR(m.phase_margin_deg, 21.39, 21.39 * kPublishedRelative);
  EXPECT_NEAR(m.phase_margin_radps, 0.6823, 0.6823 * kPublishedRelative);
  // Sector margin: min Re L of this loop is below -1/GM.
  EXPECT_LT(m.min_real, -0.5 + 1e-9);
}

TEST(Margins, DiscreteLoopMatchesDelayMarginPrediction) {
  // A pure delay e^{-sT d} on an integrator k/s has PM = 90 deg - w_c d T (w_c = k); the
  // ZOH-discretised integrator with d samples of delay: the loop at the input of the ZOH is
  // k T / (z - 1) z^-d; its gain margin is found where Im L = 0. Check the delay margin
  // against the analytic continuous-time value for a small kT (discretisation ~ half a sample).
  const double T = 1e-3;
  const double k = 5.0;
  const int d = 2;
  const auto loop = [&](double w) {
    const Complex z = std::polar(1.0, w * T);
    return k * T / (z - 1.0) * std::pow(z, -d);
  };
  MarginOptions o;
  o.sample_time_s = T;
  o.w_min_radps = 0.1;
  o.w_max_radps = 1e5;
  const LoopMargins m = computeMargins(loop, o);
  // Continuous equivalent: k/s e^{-s (d + 1/2) T}: PM = 90 deg - k (d + 1/2) T rad.
  const double pm = 90.0 - k * (d + 0.5) * T * 180.0 / std::numbers::pi;
  EXPECT_NEAR(m.phase_margin_deg, pm, 0.01);
  EXPECT_NEAR(m.phase_margin_radps, k, 1e-3 * k);
}

// Truncated Taylor series with scaling and squaring: an exponential independent of Eigen's
// Pade-based MatrixExponential.
Eigen::MatrixXd seriesExp(const Eigen::MatrixXd& M) {
  int squarings = 0;
  double norm = M.cwiseAbs().rowwise().sum().maxCoeff();
  while (norm > 0.1) {
    norm /= 2.0;
    ++squarings;
  }
  const Eigen::MatrixXd A = M / std::pow(2.0, squarings);
  Eigen::MatrixXd term = Eigen::MatrixXd::Identity(M.rows(), M.cols());
  Eigen::MatrixXd sum = term;
  for (int k = 1; k < 30; ++k) {
    term = term * A / k;
    sum += term;
  }
  for (int i = 0; i < squarings; ++i) sum = sum * sum;
  return sum;
}

TEST(Discretization, FirstOrderZohIsAnalytic) {
  // x' = -x/tau + (K/tau) u: Phi = e^{-T/tau}, Gamma = K (1 - e^{-T/tau}).
  const double tau = 0.02;
  const double K = 3.0;
  const double T = 1e-3;
  StateSpace c{Eigen::MatrixXd::Constant(1, 1, -1.0 / tau), Eigen::MatrixXd::Constant(1, 1, K / tau),
               Eigen::MatrixXd::Constant(1, 1, 1.0), Eigen::MatrixXd::Zero(1, 1), 0.0};
  const StateSpace d = discretizeZoh(c, T);
  EXPECT_NEAR(d.A(0, 0), std::exp(-T / tau), 1e-14);
  EXPECT_NEAR(d.B(0, 0), K * (1.0 - std::exp(-T / tau)), 1e-14);
  EXPECT_EQ(d.sample_time_s, T);
}

TEST(Discretization, JointPlantZohMatchesSeriesExponential) {
  // The stiff joint (hydraulic poles near 100 Hz, spool at 150 Hz): Phi against the series,
  // Gamma against the integral int_0^T e^{A t} B dt by composite Simpson with the series.
  const auto& cfg = test::dtsPlant();
  const auto& model = test::dtsModel();
  JointPlantModel jm;
  jm.joint = cfg.joints[3];
  const int idx = model.jointIndex(jm.joint.name);
  plant::UserArmParams user = cfg.user_arm;
  user.enabled = true;
  jm.load = jointLoadFromArm(model, user, idx, model.defaultPosture());
  const OperatingPoint op = solveOperatingPoint(jm, model.defaultPosture()[idx]);
  const JointLinearModel lin = linearizeJoint(jm, op);
  const double T = 1e-3;
  const StateSpace d = discretizeZoh(lin.plant, T);
  // The series on the physically scaled states (spool 1, spool rate 1e3/s, pressures 1e7 Pa,
  // angle 1 rad, velocity 1 rad/s): exp(A) = S exp(S^-1 A S) S^-1.
  const Eigen::VectorXd s = (Eigen::VectorXd(6) << 1.0, 1e3, 1e7, 1e7, 1.0, 1.0).finished();
  const auto scaledExp = [&](double t) {
    const Eigen::MatrixXd As = s.cwiseInverse().asDiagonal() * lin.plant.A * s.asDiagonal();
    return Eigen::MatrixXd(s.asDiagonal() * seriesExp(As * t) * s.cwiseInverse().asDiagonal());
  };
  const Eigen::MatrixXd phi = scaledExp(T);
  // Entry by entry, relative to the entry's row and column scale.
  for (int r = 0; r < 6; ++r) {
    for (int c = 0; c < 6; ++c) {
      EXPECT_NEAR(d.A(r, c), phi(r, c), 1e-9 * s[r] / s[c]) << "Phi(" << r << ", " << c << ")";
    }
  }
  const int n = 200;
  Eigen::MatrixXd gamma = Eigen::MatrixXd::Zero(lin.plant.A.rows(), lin.plant.B.cols());
  for (int i = 0; i <= n; ++i) {
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    gamma += w * scaledExp(T * i / n) * lin.plant.B;
  }
  gamma *= T / (3.0 * n);
  for (int c = 0; c < gamma.cols(); ++c) {
    for (int r = 0; r < 6; ++r) {
      EXPECT_NEAR(d.B(r, c), gamma(r, c), 1e-7 * gamma.col(c).cwiseQuotient(s).cwiseAbs().maxCoeff() * s[r])
          << "Gamma(" << r << ", " << c << ")";
    }
  }
}

TEST(Discretization, InputDelayShiftsTheResponse) {
  // y[k] of a delayed system equals y[k - d] of the undelayed one for the same input sequence.
  StateSpace c{(Eigen::MatrixXd(2, 2) << 0, 1, -4, -0.4).finished(), (Eigen::MatrixXd(2, 1) << 0, 1).finished(),
               (Eigen::MatrixXd(1, 2) << 1, 0).finished(), Eigen::MatrixXd::Zero(1, 1), 0.0};
  const StateSpace d0 = discretizeZoh(c, 0.01);
  const int delay = 3;
  const StateSpace d3 = addInputDelay(d0, delay);
  Eigen::VectorXd x0 = Eigen::VectorXd::Zero(2);
  Eigen::VectorXd x3 = Eigen::VectorXd::Zero(2 + delay);
  std::vector<double> y0;
  std::vector<double> y3;
  for (int k = 0; k < 50; ++k) {
    const double u = std::sin(0.3 * k) + (k == 0 ? 1.0 : 0.0);
    y0.push_back((d0.C * x0)(0));
    y3.push_back((d3.C * x3)(0));
    x0 = d0.A * x0 + d0.B * u;
    x3 = d3.A * x3 + d3.B * u;
  }
  for (int k = delay; k < 50; ++k) EXPECT_NEAR(y3[k], y0[k - delay], 1e-14);
}

class JointLinearization : public ::testing::TestWithParam<int> {};

TEST_P(JointLinearization, MatchesFiniteDifferencesOfThePlantRhs) {
  const auto& cfg = test::dtsPlant();
  const auto& model = test::dtsModel();
  const int k = GetParam();
  plant::JointParams joint = cfg.joints[static_cast<std::size_t>(k)];
  const int idx = model.jointIndex(joint.name);
  plant::UserArmParams user = cfg.user_arm;
  user.enabled = true;
  const Eigen::VectorXd posture = model.defaultPosture();
  JointPlantModel jm;
  jm.joint = joint;
  jm.load = jointLoadFromArm(model, user, idx, posture);
  const OperatingPoint op = solveOperatingPoint(jm, posture[idx]);
  const JointLinearModel lin = linearizeJoint(jm, op, FrictionLinearization::kTangent);

  // The plant itself in single-joint mode with the same user arm.
  plant::ArmPlant p;
  p.configure(model, {joint}, posture, user, cfg.solver, 1);
  plant::PlantCommand cmd = plant::PlantCommand::zero(1);
  cmd.command[0] = op.command;
  p.setCommand(cmd);
  Eigen::VectorXd y = op.state;
  Eigen::VectorXd f0(6);
  p.evaluateRhs(y.data(), f0.data());
  // The trim is an equilibrium of the plant's RHS (pressures in Pa/s against beta).
  EXPECT_LT(std::abs(f0[kVelocity]), 1e-6);
  EXPECT_LT(std::abs(f0[kPressureA]), 1e-3);
  EXPECT_LT(std::abs(f0[kPressureB]), 1e-3);
  EXPECT_LT(std::abs(f0[kSpoolRate]), 1e-6);
  // Central differences, scaled per state.
  const double scale[6] = {1e-4, 1e-2, 1e3, 1e3, 1e-5, 1e-6};
  Eigen::MatrixXd fd(6, 6);
  for (int c = 0; c < 6; ++c) {
    Eigen::VectorXd yp = y;
    Eigen::VectorXd ym = y;
    yp[c] += scale[c];
    ym[c] -= scale[c];
    Eigen::VectorXd fp(6);
    Eigen::VectorXd fm(6);
    p.evaluateRhs(yp.data(), fp.data());
    p.evaluateRhs(ym.data(), fm.data());
    fd.col(c) = (fp - fm) / (2.0 * scale[c]);
  }
  for (int r = 0; r < 6; ++r) {
    const double row_scale = std::max(fd.row(r).cwiseAbs().maxCoeff(), 1e-12);
    EXPECT_MATRIX_NEAR(lin.plant.A.row(r), fd.row(r), 1e-5 * row_scale) << "row " << r << " of " << joint.name;
  }
  // Input columns: the valve command and the user's torque.
  const double du = 1e-3;
  Eigen::VectorXd fp(6);
  Eigen::VectorXd fm(6);
  cmd.command[0] = op.command + du;
  p.setCommand(cmd);
  p.evaluateRhs(y.data(), fp.data());
  cmd.command[0] = op.command - du;
  p.setCommand(cmd);
  p.evaluateRhs(y.data(), fm.data());
  EXPECT_MATRIX_NEAR(lin.plant.B.col(kInCommand), (fp - fm) / (2.0 * du),
                     1e-6 * lin.plant.B.col(kInCommand).cwiseAbs().maxCoeff());
  cmd.command[0] = op.command;
  cmd.tau_user_nm[0] = 1e-3;
  p.setCommand(cmd);
  p.evaluateRhs(y.data(), fp.data());
  const double cell_p = p.transmittedTorque(0);
  cmd.tau_user_nm[0] = -1e-3;
  p.setCommand(cmd);
  p.evaluateRhs(y.data(), fm.data());
  const double cell_m = p.transmittedTorque(0);
  EXPECT_MATRIX_NEAR(lin.plant.B.col(kInUserTorque), (fp - fm) / 2e-3, 1e-8);
  EXPECT_NEAR(lin.plant.D(kOutTorqueCell, kInUserTorque), (cell_p - cell_m) / 2e-3, 1e-9);
}

INSTANTIATE_TEST_SUITE_P(AllJoints, JointLinearization, ::testing::Range(0, 7));

TEST(JointLinearizationFriction, StribeckWorstSlopeIsTheSteepestSlopeOfThePlantsFrictionLaw) {
  // Far above the tanh smoothing velocity the plant's friction law (H7) is the Stribeck curve
  // plus viscous friction: its smallest slope over a dense velocity grid (central differences)
  // is the viscous coefficient plus stribeckWorstSlope().
  plant::FrictionParams f;
  f.coulomb_nm = 0.5;
  f.static_nm = 0.75;
  f.stribeck_velocity_radps = 0.05;
  f.viscous_nms_per_rad = 0.1;
  f.smoothing_velocity_radps = 1e-5;
  double steepest = std::numeric_limits<double>::infinity();
  for (int i = 1; i <= 20000; ++i) {
    const double w = 0.002 + 0.2 * i / 20000.0;
    const double h = 1e-7;
    steepest =
        std::min(steepest, (plant::frictionTorque(f, w + h).value - plant::frictionTorque(f, w - h).value) / (2.0 * h));
  }
  EXPECT_NEAR(f.viscous_nms_per_rad + stribeckWorstSlope(f), steepest, 1e-4);
  EXPECT_LT(stribeckWorstSlope(f), 0.0);
  f.static_nm = f.coulomb_nm;
  EXPECT_EQ(stribeckWorstSlope(f), 0.0);
}

TEST(ControllerLinearForm, MatchesStepJointControllerInTheLinearRegion) {
  // Drive stepJointController() and the linear form with the same small inputs (inside the
  // boundary layer), with both filters and a wall, and compare the commands sample by sample.
  for (controllers::ControllerKind kind :
       {controllers::ControllerKind::kAdmittance, controllers::ControllerKind::kTorquePid}) {
    controllers::JointGains g = test::dtsGains().joints[3];
    g.torque_filter_hz = 40.0;
    g.error_rate_filter_hz = 80.0;
    g.sliding_mode.boundary_layer_radps = 50.0;  // wide: stays linear
    g.torque_pid.ki_v_per_nms = 0.5;
    g.torque_pid.kd_vs_per_nm = 0.002;
    g.torque_pid.integral_limit_v = 1e3;
    const LoopSetup setup;
    const VirtualWall wall{300.0, 2.0};
    const double slope = 1.7;  // gravity compensation slope g'(q0)
    const StateSpace c = controllerLinear(g, kind, wall, slope, setup);
    const controllers::JointControllerModel m = controllers::makeJointControllerModel(g, kind, setup.control_period_s);
    controllers::JointControllerData data;
    const double q0 = 0.3;
    const double g0 = 2.0;
    controllers::resetJointController(m, data, q0);
    // The first step initialises the controller's filters: feed the trim once.
    controllers::JointInput in0{q0, g0, 0.0, g0};
    (void)controllers::stepJointController(m, data, in0);
    Eigen::VectorXd x = Eigen::VectorXd::Zero(c.numStates());
    double worst = 0.0;
    double peak = 0.0;
    double dq_prev = 0.0;
    for (int k = 0; k < 400; ++k) {
      const double dq = 1e-3 * std::sin(0.05 * k) + 2e-4 * std::cos(0.31 * k);
      const double dcell = 0.2 * std::sin(0.021 * k + 0.4);
      // The wall as the loop renders it: tau_env = -K_w dq - B_w (dq - dq_prev) / T.
      const double tau_env =
          -(wall.stiffness_nm_per_rad * dq + wall.damping_nms_per_rad * (dq - dq_prev) / setup.control_period_s);
      dq_prev = dq;
      const controllers::JointInput in{q0 + dq, g0 + dcell, tau_env, g0 + slope * dq};
      const double u = controllers::stepJointController(m, data, in);
      ASSERT_FALSE(data.saturated);
      Eigen::Vector2d y(dq, dcell);
      const double ul = (c.C * x + c.D * y)(0);
      x = c.A * x + c.B * y;
      worst = std::max(worst, std::abs(u - ul));
      peak = std::max(peak, std::abs(u));
    }
    EXPECT_GT(peak, 1e-3);
    EXPECT_LT(worst, 1e-9 * std::max(1.0, peak)) << controllers::controllerKindName(kind);
  }
}

TEST(ZWidth, ColgateVirtualWallCondition) {
  // Colgate & Schenkel (1997): a mass-damper with physical damping b renders K + B(1 - z^-1)/T
  // passively iff b > K T / 2 + |B|: K_max = 2 (b - |B|) / T.
  const double b = 2.0;
  const double T = 1e-3;
  const std::vector<double> dampings = {-1.0, 0.0, 0.25, 0.5, 1.0, 1.5};
  const std::vector<ZWidthPoint> z = massDamperZWidth(b, T, dampings);
  ASSERT_EQ(z.size(), dampings.size());
  for (const ZWidthPoint& p : z) {
    const double expected = 2.0 * (b - std::abs(p.damping_nms_per_rad)) / T;
    EXPECT_NEAR(p.max_stiffness_nm_per_rad, expected, kColgateRelative * expected) << "B = " << p.damping_nms_per_rad;
  }
  // Too much wall damping: nothing is passive.
  EXPECT_EQ(massDamperZWidth(b, T, {2.5})[0].max_stiffness_nm_per_rad, 0.0);
}

}  // namespace
}  // namespace fullarm::design
