#include "fullarm/design/linear_analysis.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "fullarm/controllers/joint_controller.hpp"

namespace fullarm::design {

namespace {

using Complex = std::complex<double>;
constexpr int kBisectionSteps = 50;
constexpr double kGainScaleSearchMax = 1e4;
constexpr double kGainScaleSearchMin = 1e-4;

void checkSetup(const LoopSetup& s) {
  if (!(s.control_period_s > 0.0) || !std::isfinite(s.control_period_s)) {
    throw std::invalid_argument("loop setup: control_period_s must be finite and > 0");
  }
  if (s.delay_samples < 0) throw std::invalid_argument("loop setup: delay_samples must be >= 0");
  if (!(s.f_min_hz > 0.0) || !(s.f_min_hz < 0.5 / s.control_period_s)) {
    throw std::invalid_argument("loop setup: f_min_hz must be in (0, Nyquist)");
  }
  if (s.grid_points < 16) throw std::invalid_argument("loop setup: grid_points must be >= 16");
}

// The plant and controller with the loop open at the applied command: input u (applied),
// outputs [v (controller output), q]; states [plant (7), controller]. Also the tau_user input
// column of the plant for the closed loop.
struct OpenLoop {
  StateSpace sys;  // input u; output v
  Eigen::MatrixXd b_user;
  Eigen::Index plant_states = 0;
};

OpenLoop openLoop(const DiscreteJointPlant& plant, const StateSpace& ctrl) {
  const StateSpace& p = plant.discrete;
  const Eigen::Index np = p.numStates();
  const Eigen::Index nc = ctrl.numStates();
  OpenLoop o;
  o.plant_states = np;
  StateSpace& s = o.sys;
  s.sample_time_s = p.sample_time_s;
  s.A = Eigen::MatrixXd::Zero(np + nc, np + nc);
  s.A.topLeftCorner(np, np) = p.A;
  s.A.bottomLeftCorner(nc, np) = ctrl.B * p.C;
  s.A.bottomRightCorner(nc, nc) = ctrl.A;
  s.B = Eigen::MatrixXd::Zero(np + nc, 1);
  s.B.topRows(np) = p.B.col(kInCommand);
  s.C = Eigen::MatrixXd::Zero(1, np + nc);
  s.C.leftCols(np) = ctrl.D * p.C;
  s.C.rightCols(nc) = ctrl.C;
  s.D = Eigen::MatrixXd::Zero(1, 1);
  o.b_user = Eigen::MatrixXd::Zero(np + nc, 1);
  o.b_user.topRows(np) = p.B.col(kInUserTorque);
  return o;
}

// Closes the loop with `delay` registers: u_applied = v delayed, scaled by `scale`.
StateSpace closeLoop(const OpenLoop& o, int delay, double scale) {
  const StateSpace& s = o.sys;
  const Eigen::Index n = s.numStates();
  const Eigen::Index N = n + delay;
  StateSpace c;
  c.sample_time_s = s.sample_time_s;
  c.A = Eigen::MatrixXd::Zero(N, N);
  c.B = Eigen::MatrixXd::Zero(N, 1);
  c.C = Eigen::MatrixXd::Zero(2, N);  // [q, u_applied]
  c.D = Eigen::MatrixXd::Zero(2, 1);
  c.A.topLeftCorner(n, n) = s.A;
  c.B.topRows(n) = o.b_user;
  c.C(0, kAngle) = 1.0;
  if (delay == 0) {
    c.A.topLeftCorner(n, n) += scale * s.B * s.C;
    c.C.row(1).head(n) = scale * s.C;
  } else {
    c.A.block(0, n + delay - 1, n, 1) = scale * s.B;
    c.A.block(n, 0, 1, n) = s.C;  // r_1[k+1] = v[k]
    for (int i = 1; i < delay; ++i) c.A(n + i, n + i - 1) = 1.0;
    c.C(1, n + delay - 1) = scale;
  }
  return c;
}

double radiusOf(const OpenLoop& o, int delay, double scale) {
  return spectralRadius(closeLoop(o, delay, scale).A);
}

bool stableRadius(double rho) {
  return rho < 1.0 + kMarginalPoleTolerance;
}

// Largest gain scale above 1 (or below, for the lower limit) that keeps the loop stable.
double scaleLimit(const OpenLoop& o, int delay, bool upward) {
  double inside = 1.0;
  double outside = upward ? 2.0 : 0.5;
  while (stableRadius(radiusOf(o, delay, outside))) {
    inside = outside;
    outside = upward ? outside * 2.0 : outside * 0.5;
    if (outside > kGainScaleSearchMax) return std::numeric_limits<double>::infinity();
    if (outside < kGainScaleSearchMin) return 0.0;
  }
  for (int i = 0; i < kBisectionSteps; ++i) {
    const double mid = std::sqrt(inside * outside);
    if (stableRadius(radiusOf(o, delay, mid))) {
      inside = mid;
    } else {
      outside = mid;
    }
  }
  return inside;
}

StateSpace controllerFor(const PreparedJoint& joint, const controllers::JointGains& gains, const VirtualWall& wall) {
  const double slope = joint.setup.gravity_compensation ? joint.coupled.linear.device_gravity_slope_nm_per_rad : 0.0;
  return controllerLinear(gains, joint.setup.controller, wall, slope, joint.setup);
}

}  // namespace

DiscreteJointPlant discretizeJointPlant(const JointLinearModel& linear, const plant::JointParams& joint,
                                        double period_s) {
  const StateSpace zoh = discretizeZoh(linear.plant, period_s);
  const double fc = joint.sensor_noise.torque_filter_hz;
  const double a = fc > 0.0 ? std::exp(-2.0 * std::numbers::pi * fc * period_s) : 0.0;
  DiscreteJointPlant d;
  d.linear = linear;
  d.sensor_filter_coefficient = a;
  StateSpace& s = d.discrete;
  s.sample_time_s = period_s;
  const Eigen::Index n = zoh.numStates();
  s.A = Eigen::MatrixXd::Zero(n + 1, n + 1);
  s.B = Eigen::MatrixXd::Zero(n + 1, 2);
  s.C = Eigen::MatrixXd::Zero(2, n + 1);
  s.D = Eigen::MatrixXd::Zero(2, 2);
  s.A.topLeftCorner(n, n) = zoh.A;
  s.B.topRows(n) = zoh.B;
  // Load-cell sample at the end of the period (inputs held over it), then the filter
  // tau_f[k+1] = a tau_f[k] + (1 - a) tau_cell(t_{k+1}) (plant::sampleJointSensors).
  const Eigen::RowVectorXd c_cell = zoh.C.row(kOutTorqueCell);
  const Eigen::RowVectorXd d_cell = zoh.D.row(kOutTorqueCell);
  s.A.block(n, 0, 1, n) = (1.0 - a) * c_cell * zoh.A;
  s.A(n, n) = a;
  s.B.row(n) = (1.0 - a) * (c_cell * zoh.B + d_cell);
  s.C(0, kAngle) = 1.0;
  s.C(1, n) = 1.0;
  return d;
}

// Eq. (8): the controller's linear form in the boundary layer (reports/equations.md).
StateSpace controllerLinear(const controllers::JointGains& gains, controllers::ControllerKind kind,
                            const VirtualWall& wall, double gravity_slope_nm_per_rad, const LoopSetup& setup) {
  checkSetup(setup);
  const double T = setup.control_period_s;
  const controllers::JointControllerModel m = controllers::makeJointControllerModel(gains, kind, T);
  const bool admittance = kind == controllers::ControllerKind::kAdmittance;
  const double a = m.torque_filter_pole;
  const double b = admittance ? m.error_rate_filter_pole : 0.0;
  // State columns, then the inputs [q, tau_load_cell].
  int n = 0;
  const int i0 = n++;  // admittance: theta_m; PID: integral
  const int i1 = n++;  // admittance: omega_m; PID: tau_prev
  const int iqp = n++;
  const int iep = admittance ? n++ : -1;
  const int ird = b > 0.0 ? n++ : -1;
  const int itf = a > 0.0 ? n++ : -1;
  const int iq = n;
  const int icell = n + 1;
  using Row = Eigen::RowVectorXd;
  const auto unit = [&](int i) {
    Row r = Row::Zero(n + 2);
    r[i] = 1.0;
    return r;
  };
  const auto zero = [&]() { return Row::Zero(n + 2); };
  // Step 1: torque filter on tau_u + tau_ga = -load cell (exact ZOH low-pass, pole a).
  const Row f = (itf >= 0 ? Row(a * unit(itf)) : zero()) - (1.0 - a) * unit(icell);
  // Step 2, Eq. (4): tau = tau_f + tau_env + g(q), with tau_env = -K_w q - B_w qdot.
  const Row qdot = (unit(iq) - unit(iqp)) / T;
  const Row tau =
      f + gravity_slope_nm_per_rad * unit(iq) - wall.stiffness_nm_per_rad * unit(iq) - wall.damping_nms_per_rad * qdot;
  Eigen::MatrixXd next(n, n + 2);
  next.setZero();
  Row u;
  if (admittance) {
    // Step 3: Eq. (3) with theta_d = q, exact ZOH with tau + K_m q held.
    const Row input = tau + gains.impedance.stiffness_nm_per_rad * unit(iq);
    const Row theta = m.phi[0][0] * unit(i0) + m.phi[0][1] * unit(i1) + m.gamma[0] * input;
    const Row omega = m.phi[1][0] * unit(i0) + m.phi[1][1] * unit(i1) + m.gamma[1] * input;
    // Eq. (5)-(6): e = theta_m[k+1] - q, e' = filtered (e - e_prev)/T, s = e' + lambda e.
    const Row e = theta - unit(iq);
    const Row rate = (ird >= 0 ? Row(b * unit(ird)) : zero()) + (1.0 - b) * (e - unit(iep)) / T;
    const Row s = rate + gains.sliding_mode.lambda_per_s * e;
    // Eq. (7) in the boundary layer (Eq. 8): u = (B_o / eps) s.
    u = gains.sliding_mode.valve_bound_v / gains.sliding_mode.boundary_layer_radps * s;
    next.row(i0) = theta;
    next.row(i1) = omega;
    next.row(iep) = e;
    if (ird >= 0) next.row(ird) = rate;
  } else {
    // Torque PID: integral += ki T tau (clamp inactive), u = kp tau + integral + kd (tau - tau_prev)/T.
    const controllers::TorquePidParams& pid = gains.torque_pid;
    const Row integral = unit(i0) + pid.ki_v_per_nms * T * tau;
    u = pid.kp_v_per_nm * tau + integral + pid.kd_vs_per_nm * (tau - unit(i1)) / T;
    next.row(i0) = integral;
    next.row(i1) = tau;
  }
  next.row(iqp) = unit(iq);
  if (itf >= 0) next.row(itf) = f;
  StateSpace c;
  c.sample_time_s = T;
  c.A = next.leftCols(n);
  c.B = next.rightCols(2);
  c.C = u.head(n);
  c.D = u.tail(2);
  return c;
}

PreparedJoint prepareJoint(const JointPlantModel& model, const OperatingPoint& op, const LoopSetup& setup) {
  checkSetup(setup);
  PreparedJoint p;
  p.model = model;
  p.setup = setup;
  p.coupled = discretizeJointPlant(linearizeJoint(model, op, setup.friction), model.joint, setup.control_period_s);
  JointPlantModel device = model;
  device.include_user = false;
  p.device = discretizeJointPlant(linearizeJoint(device, op, setup.friction), model.joint, setup.control_period_s);
  return p;
}

double closedLoopSpectralRadius(const PreparedJoint& joint, const controllers::JointGains& gains,
                                const VirtualWall& wall) {
  const OpenLoop o = openLoop(joint.coupled, controllerFor(joint, gains, wall));
  return radiusOf(o, joint.setup.delay_samples, 1.0);
}

StateSpace closedLoopSystem(const PreparedJoint& joint, const controllers::JointGains& gains, const VirtualWall& wall) {
  const OpenLoop o = openLoop(joint.coupled, controllerFor(joint, gains, wall));
  return closeLoop(o, joint.setup.delay_samples, 1.0);
}

Eigen::VectorXcd closedLoopPoles(const PreparedJoint& joint, const controllers::JointGains& gains,
                                 const VirtualWall& wall) {
  const OpenLoop o = openLoop(joint.coupled, controllerFor(joint, gains, wall));
  return eigenvalues(closeLoop(o, joint.setup.delay_samples, 1.0).A);
}

namespace {

Complex impedanceWith(const PreparedJoint& joint, const StateSpace& ctrl, double w) {
  const double T = joint.setup.control_period_s;
  const Eigen::MatrixXcd P = frequencyResponse(joint.device.linear.plant, w);  // [q, qd, tau_cell] x [u, tau]
  const Eigen::MatrixXcd K = frequencyResponse(ctrl, w);                       // 1 x [q, tau_meas]
  const Complex z = std::polar(1.0, w * T);
  const double a = joint.device.sensor_filter_coefficient;
  const Complex sensor = (1.0 - a) / (1.0 - a / z);
  const Complex zoh = std::abs(w * T) < 1e-9 ? Complex(1.0) : (1.0 - 1.0 / z) / Complex(0.0, w * T);
  const Complex pre = zoh * std::pow(z, -joint.setup.delay_samples);
  const Complex hq = pre * K(0, 0);
  const Complex ht = pre * K(0, 1) * sensor;
  const Complex h_yu = hq * P(kOutAngle, kInCommand) + ht * P(kOutTorqueCell, kInCommand);
  const Complex h_yt = hq * P(kOutAngle, kInUserTorque) + ht * P(kOutTorqueCell, kInUserTorque);
  const Complex u_per_tau = h_yt / (1.0 - h_yu);
  const Complex admittance = P(kOutVelocity, kInUserTorque) + P(kOutVelocity, kInCommand) * u_per_tau;
  return 1.0 / admittance;
}

}  // namespace

// T6: rendered impedance of the sampled loop (reports/equations.md).
std::complex<double> renderedImpedance(const PreparedJoint& joint, const controllers::JointGains& gains,
                                       const VirtualWall& wall, double w) {
  return impedanceWith(joint, controllerFor(joint, gains, wall), w);
}

// T4: circle criterion for the saturation (reports/equations.md).
LinearChecks analyzePrepared(const PreparedJoint& joint, const controllers::JointGains& gains, const VirtualWall& wall,
                             bool with_frequency_data, bool with_gain_limits) {
  const LoopSetup& setup = joint.setup;
  const StateSpace ctrl = controllerFor(joint, gains, wall);
  const OpenLoop o = openLoop(joint.coupled, ctrl);
  const OpenLoop od = openLoop(joint.device, ctrl);
  const int d = setup.delay_samples;
  const double T = setup.control_period_s;
  LinearChecks r;
  const StateSpace closed = closeLoop(o, d, 1.0);
  r.closed_loop_poles = eigenvalues(closed.A);
  r.spectral_radius = r.closed_loop_poles.size() > 0 ? r.closed_loop_poles.cwiseAbs().maxCoeff() : 0.0;
  r.device_spectral_radius = radiusOf(od, d, 1.0);
  r.open_loop_spectral_radius = spectralRadius(o.sys.A);
  r.stable = stableRadius(r.spectral_radius);

  // L at the applied valve command: L = -z^-d V(z).
  const auto loop = [&](double w) {
    const Complex z = std::polar(1.0, w * T);
    return -std::pow(z, -d) * frequencyResponse(o.sys, w)(0, 0);
  };
  MarginOptions mo;
  mo.w_min_radps = 2.0 * std::numbers::pi * setup.f_min_hz;
  mo.w_max_radps = std::numbers::pi / T;
  mo.grid_points = setup.grid_points;
  mo.sample_time_s = T;
  r.margins = computeMargins(loop, mo);
  r.low_gain_stable = r.stable;
  for (double kappa : kSectorScales) r.low_gain_stable = r.low_gain_stable && stableRadius(radiusOf(o, d, kappa));
  r.sector_ok = r.low_gain_stable && r.margins.min_real > -1.0;
  r.gain_scale_upper = r.stable && with_gain_limits ? scaleLimit(o, d, true) : 0.0;
  r.gain_scale_lower = r.stable && with_gain_limits ? scaleLimit(o, d, false) : 0.0;

  // Rendered impedance of the device on the grid.
  const Eigen::VectorXd w = logspace(mo.w_min_radps, mo.w_max_radps, setup.grid_points);
  r.min_real_impedance = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < w.size(); ++i) {
    const Complex z = impedanceWith(joint, ctrl, w[i]);
    if (z.real() < r.min_real_impedance) {
      r.min_real_impedance = z.real();
      r.min_real_impedance_hz = w[i] / (2.0 * std::numbers::pi);
    }
    if (with_frequency_data) {
      r.frequency.frequency_hz.push_back(w[i] / (2.0 * std::numbers::pi));
      r.frequency.loop.push_back(loop(w[i]));
      r.frequency.impedance.push_back(z);
    }
  }
  r.passive = r.min_real_impedance >= 0.0 && stableRadius(r.device_spectral_radius);
  return r;
}

LinearChecks analyzeJoint(const JointPlantModel& model, const OperatingPoint& op, const controllers::JointGains& gains,
                          const VirtualWall& wall, const LoopSetup& setup) {
  return analyzePrepared(prepareJoint(model, op, setup), gains, wall, true);
}

double wallStiffnessLimit(const PreparedJoint& joint, const controllers::JointGains& gains, double damping,
                          double k_min, double k_max) {
  if (!(k_min > 0.0) || !(k_max > k_min)) throw std::invalid_argument("wallStiffnessLimit: expected 0 < k_min < k_max");
  const auto stable = [&](double k) {
    return stableRadius(closedLoopSpectralRadius(joint, gains, VirtualWall{k, damping}));
  };
  if (!stable(k_min)) return 0.0;
  if (stable(k_max)) return k_max;
  double lo = k_min;
  double hi = k_max;
  for (int i = 0; i < kBisectionSteps; ++i) {
    const double mid = std::sqrt(lo * hi);
    if (stable(mid)) {
      lo = mid;
    } else {
      hi = mid;
    }
    if (hi / lo < 1.0 + 1e-6) break;
  }
  return lo;
}

std::vector<ZWidthPoint> jointZWidth(const PreparedJoint& joint, const controllers::JointGains& gains,
                                     const std::vector<double>& dampings) {
  std::vector<ZWidthPoint> out;
  for (double b : dampings) out.push_back({b, wallStiffnessLimit(joint, gains, b)});
  return out;
}

// T5: Colgate-Schenkel passivity of a sampled wall (reports/equations.md).
double colgateRequiredDamping(const std::function<std::complex<double>(std::complex<double>)>& H, double T,
                              int points) {
  if (!(T > 0.0) || points < 2) throw std::invalid_argument("colgateRequiredDamping: expected T > 0, points >= 2");
  double worst = -std::numeric_limits<double>::infinity();
  for (int i = 1; i <= points; ++i) {
    const double x = std::numbers::pi * i / points;  // w T in (0, pi]
    const Complex z = std::polar(1.0, x);
    const double value = T / (2.0 * (1.0 - std::cos(x))) * ((1.0 - 1.0 / z) * H(z)).real();
    worst = std::max(worst, value);
  }
  return worst;
}

// T5: Colgate-Schenkel passivity of a sampled wall (reports/equations.md).
std::vector<ZWidthPoint> massDamperZWidth(double b, double T, const std::vector<double>& wall_dampings) {
  if (!(b > 0.0) || !(T > 0.0)) throw std::invalid_argument("massDamperZWidth: expected b > 0 and T > 0");
  std::vector<ZWidthPoint> out;
  for (double B : wall_dampings) {
    const auto required = [&](double K) {
      return colgateRequiredDamping([&](Complex z) { return K + B * (1.0 - 1.0 / z) / T; }, T);
    };
    double lo = 0.0;
    if (!(required(lo) < b)) {
      out.push_back({B, 0.0});
      continue;
    }
    double hi = 1.0;
    while (required(hi) < b) hi *= 2.0;
    for (int i = 0; i < kBisectionSteps; ++i) {
      const double mid = 0.5 * (lo + hi);
      if (required(mid) < b) {
        lo = mid;
      } else {
        hi = mid;
      }
    }
    out.push_back({B, lo});
  }
  return out;
}

}  // namespace fullarm::design
