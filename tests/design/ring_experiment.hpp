#pragma once
// Ring-down experiments on one joint, linear and nonlinear (is the tuner's worst-case Ms
// real?). Shared by tests/design/linear_vs_nonlinear_test.cpp and bench/ms_worst_case.cpp.
//
// The nonlinear side is validate's closed-loop harness reduced to a hold at the linearisation's
// trim: the joint of variationScenario() on validate's scenario (CVODES plant), with ideal sensors
// (24-bit converters over the same span, no noise or bias), no Coulomb/static friction and the
// tight reference tolerances, started at the trim (spool, pressures, q) that the linearisation
// uses, the user applied as validate's harness applies it (K_h (q0 - q) - B_h qd from the true
// state, held over the period), the trim command fed forward, and a Hann-windowed burst added to
// the applied valve command (the loop break of L). The linear side is the same experiment on the
// discrete closed loop of the prepared joint, assembled here from the public pieces (discrete
// plant, controllerLinear, delay register), not with linear_analysis.cpp's closeLoop().

#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

#include "design_fixture.hpp"
#include "fullarm/controllers/joint_controller.hpp"
#include "fullarm/design/closed_loop.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/tune_arm.hpp"
#include "fullarm/design/tuner.hpp"
#include "fullarm/design/validation.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::design::test {

// The scenario with ideal sensors (24-bit converters over the same span, no noise or bias) and/or
// without Coulomb and static friction (the viscous term stays, as in the linear model).
inline void idealize(JointScenario& sc, bool ideal_sensors, bool no_coulomb) {
  if (no_coulomb) {
    sc.joint.friction.coulomb_nm = 0.0;
    sc.joint.friction.static_nm = 0.0;
  }
  if (ideal_sensors) {
    sc.joint.sensor_noise.angle_noise_rad = 0.0;
    sc.joint.sensor_noise.torque_noise_nm = 0.0;
    sc.joint.sensor_noise.torque_bias_nm = 0.0;
    constexpr double kFiner = 4096.0;  // 12 -> 24 bits over the same span
    sc.joint.potentiometer.bits = 24;
    sc.joint.potentiometer.slope_rad_per_count /= kFiner;
    sc.joint.potentiometer.offset_counts *= kFiner;
    sc.joint.torque_sensor.bits = 24;
    sc.joint.torque_sensor.slope_nm_per_count /= kFiner;
    sc.joint.torque_sensor.offset_counts *= kFiner;
  }
}

// Hann-windowed burst of `cycles` periods at f_hz, amplitude a [V], from t = 0.
inline double burst(double t, double f_hz, double cycles, double a) {
  const double len = cycles / f_hz;
  if (t < 0.0 || t >= len) return 0.0;
  const double w = 0.5 - 0.5 * std::cos(2.0 * std::numbers::pi * t / len);
  return a * w * std::sin(2.0 * std::numbers::pi * f_hz * t);
}

struct Ring {
  std::vector<double> qd;     // true joint speed [rad/s], one per period
  std::vector<double> spool;  // normalised spool position
  double trim_command_v = 0.0;
  bool solver_ok = true;
};

// validate's nonlinear joint (variationScenario on validate's scenario, CVODES) with ideal sensors
// (24-bit, no noise), no Coulomb/static friction, tight solver tolerances, started at rest at the
// linearisation's trim (q, spool, pressures), the user as validate's harness applies it (sampled
// K_h (q0 - q) - B_h qd), the trim command fed forward, and a burst added to the applied command.
inline Ring nonlinearRing(const JointScenario& nominal, const JointPlantModel& jm_v, const ModelVariation& v,
                          const controllers::JointGains& gains, double q0, double f_hz, double a_v, double duration_s) {
  ModelVariation sample = v;
  sample.index = 0;
  JointScenario sc = variationScenario(nominal, sample);
  idealize(sc, true, true);
  sc.solver = plant::tightReferenceOptions(sc.solver);
  JointPlantModel jm_nf = jm_v;
  jm_nf.joint.friction.coulomb_nm = 0.0;
  jm_nf.joint.friction.static_nm = 0.0;
  const OperatingPoint op = solveOperatingPoint(jm_nf, q0);
  plant::ArmPlant plant;
  plant.configure(sc.joint, sc.load, sc.solver, sc.noise_seed);
  plant::JointState s0;
  s0.spool = op.state[kSpool];
  s0.spool_rate_per_s = op.state[kSpoolRate];
  s0.p_a_pa = op.state[kPressureA];
  s0.p_b_pa = op.state[kPressureB];
  s0.q_rad = q0;
  plant.reset({s0});
  const controllers::JointControllerModel cm =
      controllers::makeJointControllerModel(gains, controllers::ControllerKind::kAdmittance, sc.dt_s);
  controllers::JointControllerData cd;
  controllers::resetJointController(cm, cd, plant.measurement(0).q_rad);
  const int delay = sc.delay_samples;
  std::vector<double> line(static_cast<std::size_t>(delay) + 1, 0.0);
  plant::PlantCommand cmd = plant::PlantCommand::zero(1);
  Ring r;
  r.trim_command_v = op.command;
  const long steps = std::lround(duration_s / sc.dt_s);
  for (long k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * sc.dt_s;
    const plant::JointMeasurement& m = plant.measurement(0);
    const plant::JointState st = plant.state(0);
    controllers::JointInput in;
    in.q_rad = m.q_rad;
    in.tau_load_cell_nm = m.tau_nm;
    in.tau_gravity_nm = sc.expected_gravity_cos_nm * std::cos(m.q_rad) + sc.expected_gravity_sin_nm * std::sin(m.q_rad);
    const double u = controllers::stepJointController(cm, cd, in);
    std::rotate(line.rbegin(), line.rbegin() + 1, line.rend());
    line[0] = u;
    cmd.command[0] = line[static_cast<std::size_t>(delay)] + op.command + burst(t, f_hz, 3.0, a_v);
    cmd.tau_user_nm[0] = sc.user.stiffness_nm_per_rad * (q0 - st.q_rad) - sc.user.damping_nms_per_rad * st.qd_radps;
    r.qd.push_back(st.qd_radps);
    r.spool.push_back(st.spool);
    if (!plant.step(sc.dt_s, cmd).ok()) {
      r.solver_ok = false;
      break;
    }
  }
  return r;
}

// The same experiment on the discrete linear closed loop (prepared joint, its controller, delay
// register; the burst at the applied command): speed qd per period. Built here from the public
// pieces (discrete plant, controllerLinear), not with linear_analysis.cpp's internal closeLoop().
inline Ring linearRing(const PreparedJoint& p, const controllers::JointGains& gains, double f_hz, double a_v,
                       double duration_s, Eigen::VectorXcd* poles = nullptr) {
  const StateSpace& P = p.coupled.discrete;
  const double slope = p.setup.gravity_compensation ? p.coupled.linear.device_gravity_slope_nm_per_rad : 0.0;
  const StateSpace K = controllerLinear(gains, p.setup.controller, VirtualWall{}, slope, p.setup);
  const Eigen::Index np = P.numStates(), nc = K.numStates();
  const int d = p.setup.delay_samples;
  const Eigen::Index n = np + nc + d;
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n);
  A.topLeftCorner(np, np) = P.A;
  A.block(np, 0, nc, np) = K.B * P.C;
  A.block(np, np, nc, nc) = K.A;
  // v = K.C xc + K.D P.C xp; u_applied = r_d (+ burst).
  Eigen::RowVectorXd v = Eigen::RowVectorXd::Zero(n);
  v.head(np) = K.D * P.C;
  v.segment(np, nc) = K.C;
  if (d == 0) {
    A.topRows(np) += P.B.col(kInCommand) * v;
  } else {
    A.block(0, np + nc + d - 1, np, 1) = P.B.col(kInCommand);
    A.row(np + nc) = v;
    for (int i = 1; i < d; ++i) A(np + nc + i, np + nc + i - 1) = 1.0;
  }
  b.head(np) = P.B.col(kInCommand);
  if (poles != nullptr) *poles = Eigen::EigenSolver<Eigen::MatrixXd>(A).eigenvalues();
  const double T = p.setup.control_period_s;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(n);
  Ring out;
  const long steps = std::lround(duration_s / T);
  for (long k = 0; k < steps; ++k) {
    out.qd.push_back(x[kVelocity]);
    out.spool.push_back(x[kSpool]);
    x = A * x + b * burst(static_cast<double>(k) * T, f_hz, 3.0, a_v);
  }
  return out;
}

// Least-squares Prony fit of y[begin, end) decimated by `dec` (linear prediction of order `order`,
// mean removed): the fitted pole (continuous s) nearest to s_pred.
inline std::complex<double> pronyPole(const std::vector<double>& y, std::size_t begin, std::size_t end, int dec,
                                      int order, double T, std::complex<double> s_pred) {
  std::vector<double> x;
  for (std::size_t i = begin; i < end && i < y.size(); i += static_cast<std::size_t>(dec)) x.push_back(y[i]);
  const auto n = static_cast<Eigen::Index>(x.size());
  const Eigen::Index rows = n - order;
  Eigen::MatrixXd M(rows, order);
  Eigen::VectorXd rhs(rows);
  for (Eigen::Index r = 0; r < rows; ++r) {
    rhs[r] = x[static_cast<std::size_t>(r + order)];
    for (int j = 0; j < order; ++j) M(r, j) = x[static_cast<std::size_t>(r + order - 1 - j)];
  }
  const double scale = M.cwiseAbs().maxCoeff();
  const Eigen::VectorXd a = (M / scale).colPivHouseholderQr().solve(rhs / scale);
  Eigen::MatrixXd comp = Eigen::MatrixXd::Zero(order, order);
  comp.row(0) = a.transpose();
  for (int i = 1; i < order; ++i) comp(i, i - 1) = 1.0;
  const Eigen::VectorXcd roots = Eigen::EigenSolver<Eigen::MatrixXd>(comp).eigenvalues();
  std::complex<double> best(0.0, 0.0);
  double best_dist = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < roots.size(); ++i) {
    if (std::abs(roots[i]) == 0.0) continue;
    const std::complex<double> s = std::log(roots[i]) / (T * dec);
    const double dist = std::abs(s - s_pred);
    if (dist < best_dist) {
      best_dist = dist;
      best = s;
    }
  }
  return best;
}

// Envelope check independent of the Prony fit: RMS of y over consecutive windows of whole
// periods; growth rate = slope of ln RMS; frequency from zero crossings of the whole window.
inline void envelope(const std::vector<double>& y, std::size_t begin, std::size_t end, double T, double f_hz,
                     double* sigma, double* freq) {
  const auto per = static_cast<std::size_t>(std::max(1.0, std::round(2.0 / (f_hz * T))));  // two periods
  std::vector<double> t, l;
  for (std::size_t i = begin; i + per <= end && i + per <= y.size(); i += per) {
    double mean = 0.0, sq = 0.0;
    for (std::size_t k = i; k < i + per; ++k) mean += y[k];
    mean /= static_cast<double>(per);
    for (std::size_t k = i; k < i + per; ++k) sq += (y[k] - mean) * (y[k] - mean);
    t.push_back((static_cast<double>(i) + 0.5 * static_cast<double>(per)) * T);
    l.push_back(0.5 * std::log(sq / static_cast<double>(per)));
  }
  double st = 0.0, sl = 0.0, stt = 0.0, stl = 0.0;
  const double m = static_cast<double>(t.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    st += t[i];
    sl += l[i];
    stt += t[i] * t[i];
    stl += t[i] * l[i];
  }
  *sigma = -(m * stl - st * sl) / (m * stt - st * st);
  double mean = 0.0;
  for (std::size_t k = begin; k < end; ++k) mean += y[k];
  mean /= static_cast<double>(end - begin);
  int crossings = 0;
  for (std::size_t k = begin + 1; k < end; ++k) {
    if ((y[k - 1] - mean) * (y[k] - mean) < 0.0) ++crossings;
  }
  *freq = crossings / (2.0 * static_cast<double>(end - begin) * T);
}

}  // namespace fullarm::design::test
