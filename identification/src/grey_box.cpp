#include "fullarm/identification/grey_box.hpp"

#include <Eigen/Dense>
#include <Eigen/SVD>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "fullarm/core/job_pool.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::identification {
namespace {

constexpr int kSubsteps = 4;
constexpr double kDivergedResidual = 1.0e3;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct State {
  double q = 0.0, w = 0.0, th = 0.0;
  double x = 0.0, xd = 0.0;  // spool position (in volts of command) and its rate
  double tf = 0.0;           // filtered load-cell torque
};

// Edge opening rounded over w (the plant's H2 in volts): 0 below -w, s above w, a quadratic blend
// between.
double roundedOpening(double s, double w) noexcept {
  if (w <= 0.0) return std::max(s, 0.0);
  if (s <= -w) return 0.0;
  if (s >= w) return s;
  return (s + w) * (s + w) / (4.0 * w);
}

// Friction f(w) of (I2): Coulomb and Stribeck level with a tanh-smoothed sign, plus viscous.
double friction(const GreyModel& m, double w) noexcept {
  const auto& p = m.value;
  const double r = w / m.stribeck_velocity_radps;
  const double level = p[kCoulomb] + p[kStribeck] * std::exp(-r * r);
  return level * std::tanh(w / m.coulomb_smoothing_radps) + p[kViscous] * w;
}

// The reduced joint's right-hand side, (I1)-(I2) of grey_box.hpp.
double cellTorque(const GreyModel& m, const State& x) noexcept { return x.th - friction(m, x.w); }

State rhs(const GreyModel& m, const State& x, double u, double q_ref) noexcept {
  const auto& p = m.value;
  State d;
  double drive = u;
  if (m.spool_hz > 0.0) {
    const double wn = 2.0 * std::numbers::pi * m.spool_hz;
    d.x = x.xd;
    d.xd = wn * wn * (u - x.x) - 2.0 * m.spool_damping * wn * x.xd;
    drive = x.x;
  }
  d.q = x.w;
  d.w = (cellTorque(m, x) - p[kLoadTorque] - m.load_gradient_nm_per_rad * (x.q - q_ref)) / p[kInertia];
  d.th = p[kStiffness] * (p[kFlowGain] * valveLoadFlow(m, drive + p[kValveOffset], x.th) - x.w - p[kLeakage] * x.th);
  return d;  // d.tf = 0: the load-cell filter acts on the samples (sampleLoadCell)
}

// The load cell's first-order filter on the sampled torque, as the plant's sensor model has it
// (exact ZOH discretisation, the new sample held over the period it closes):
// tf_k = a tf_{k-1} + (1 - a) tau_cell(t_k), a = exp(-2 pi f_c T).
void sampleLoadCell(const GreyModel& m, State& x, double dt) noexcept {
  if (m.torque_filter_hz <= 0.0) return;
  const double a = std::exp(-2.0 * std::numbers::pi * m.torque_filter_hz * dt);
  x.tf = a * x.tf + (1.0 - a) * cellTorque(m, x);
}

// The valve position (before the offset) whose flow balances the leakage under the static load:
// a Q(x + u_0, tau_g) = c tau_g, by bisection (Q rises with x).
double restingValve(const GreyModel& m) noexcept {
  const auto& p = m.value;
  const double target = p[kLeakage] * p[kLoadTorque] / p[kFlowGain];
  double lo = -100.0, hi = 100.0;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    (valveLoadFlow(m, mid, p[kLoadTorque]) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi) - p[kValveOffset];
}

State axpy(const State& x, double h, const State& d) noexcept {
  return {x.q + h * d.q, x.w + h * d.w, x.th + h * d.th, x.x + h * d.x, x.xd + h * d.xd, x.tf + h * d.tf};
}

// One classical RK4 step of length h under the held command u.
State rk4Step(const GreyModel& m, const State& x, double u, double q_ref, double h) noexcept {
  const State k1 = rhs(m, x, u, q_ref);
  const State k2 = rhs(m, axpy(x, 0.5 * h, k1), u, q_ref);
  const State k3 = rhs(m, axpy(x, 0.5 * h, k2), u, q_ref);
  const State k4 = rhs(m, axpy(x, h, k3), u, q_ref);
  return axpy(axpy(axpy(axpy(x, h / 6.0, k1), h / 3.0, k2), h / 3.0, k3), h / 6.0, k4);
}

double measuredTorque(const GreyModel& m, const State& x) noexcept {
  return (m.torque_filter_hz > 0.0 ? x.tf : cellTorque(m, x)) + m.value[kTorqueOffset];
}

double spread(const std::vector<double>& v) {
  double mean = 0.0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(v.size());
  double ss = 0.0;
  for (double x : v) ss += (x - mean) * (x - mean);
  const double s = std::sqrt(ss / static_cast<double>(v.size()));
  return s > 0.0 ? s : 1.0;
}

/// The free parameters in fit coordinates (log for log-scaled ones).
struct Coordinates {
  std::vector<int> index;
  std::vector<bool> log_scaled;
  Eigen::VectorXd lo, hi;

  explicit Coordinates(const FitOptions& o) {
    for (int i = 0; i < kGreyParams; ++i) {
      const ParamSpec& s = o.params[static_cast<std::size_t>(i)];
      if (!s.free) continue;
      index.push_back(i);
      log_scaled.push_back(s.log_scaled);
    }
    const auto n = static_cast<Eigen::Index>(index.size());
    lo.resize(n);
    hi.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const ParamSpec& s = o.params[static_cast<std::size_t>(index[static_cast<std::size_t>(k)])];
      lo[k] = log_scaled[static_cast<std::size_t>(k)] ? std::log(s.min) : s.min;
      hi[k] = log_scaled[static_cast<std::size_t>(k)] ? std::log(s.max) : s.max;
    }
  }
  [[nodiscard]] Eigen::VectorXd toZ(const GreyModel& m) const {
    Eigen::VectorXd z(static_cast<Eigen::Index>(index.size()));
    for (std::size_t k = 0; k < index.size(); ++k) {
      const double v = m.value[static_cast<std::size_t>(index[k])];
      z[static_cast<Eigen::Index>(k)] = log_scaled[k] ? std::log(v) : v;
    }
    return z;
  }
  [[nodiscard]] GreyModel fromZ(const GreyModel& base, const Eigen::VectorXd& z) const {
    GreyModel m = base;
    for (std::size_t k = 0; k < index.size(); ++k) {
      const double v = z[static_cast<Eigen::Index>(k)];
      m.value[static_cast<std::size_t>(index[k])] = log_scaled[k] ? std::exp(v) : v;
    }
    return m;
  }
  [[nodiscard]] Eigen::VectorXd clamp(const Eigen::VectorXd& z) const { return z.cwiseMax(lo).cwiseMin(hi); }
};

class Problem {
 public:
  Problem(const std::vector<ExperimentData>& experiments) : experiments_(experiments) {
    for (const auto& e : experiments_) {
      q_scale_.push_back(spread(e.q_rad));
      tau_scale_.push_back(spread(e.tau_nm));
      residual_count_ += 2 * static_cast<Eigen::Index>(e.q_rad.size());
    }
  }
  [[nodiscard]] Eigen::Index residualCount() const noexcept { return residual_count_; }
  std::atomic<int> evaluations{0};

  /// Thread-safe: each call simulates on its own.
  void residuals(const GreyModel& m, Eigen::VectorXd& r) {
    ++evaluations;
    r.resize(residual_count_);
    Eigen::Index at = 0;
    for (std::size_t e = 0; e < experiments_.size(); ++e) {
      const ExperimentData& x = experiments_[e];
      const Simulation s = simulateClosedLoop(m, x);
      for (std::size_t k = 0; k < x.q_rad.size(); ++k) {
        const double rq = (s.q_rad[k] - x.q_rad[k]) / q_scale_[e];
        const double rt = (s.tau_nm[k] - x.tau_nm[k]) / tau_scale_[e];
        r[at++] = s.ok && std::isfinite(rq) ? rq : kDivergedResidual;
        r[at++] = s.ok && std::isfinite(rt) ? rt : kDivergedResidual;
      }
    }
  }
  double cost(const GreyModel& m) {
    Eigen::VectorXd r;
    residuals(m, r);
    return 0.5 * r.squaredNorm();
  }

 private:
  const std::vector<ExperimentData>& experiments_;
  std::vector<double> q_scale_, tau_scale_;
  Eigen::Index residual_count_ = 0;
};

struct Polished {
  GreyModel model;
  double cost = 0.0;
  Eigen::MatrixXd jacobian;
};

// Central differences, the 2 p simulations spread over the pool.
void jacobian(Problem& problem, const Coordinates& c, const GreyModel& base, const Eigen::VectorXd& z,
              Eigen::MatrixXd& jac, core::JobPool& pool) {
  const auto p = z.size();
  jac.resize(problem.residualCount(), p);
  std::vector<Eigen::VectorXd> r(static_cast<std::size_t>(2 * p));
  auto step = [&](Eigen::Index k) {
    return c.log_scaled[static_cast<std::size_t>(k)] ? 1e-5 : 1e-5 * std::max(1.0, c.hi[k] - c.lo[k]);
  };
  pool.run(static_cast<int>(2 * p), [&](int task) {
    const Eigen::Index k = task / 2;
    Eigen::VectorXd zk = z;
    zk[k] += (task % 2 == 0 ? 1.0 : -1.0) * step(k);
    problem.residuals(c.fromZ(base, zk), r[static_cast<std::size_t>(task)]);
  });
  for (Eigen::Index k = 0; k < p; ++k) {
    jac.col(k) = (r[static_cast<std::size_t>(2 * k)] - r[static_cast<std::size_t>(2 * k + 1)]) / (2.0 * step(k));
  }
}

// Projected Levenberg-Marquardt (Marquardt's diagonal scaling) inside the box.
Polished polish(Problem& problem, const Coordinates& c, const GreyModel& start, int max_iterations,
                core::JobPool& pool) {
  Eigen::VectorXd z = c.clamp(c.toZ(start));
  Eigen::VectorXd r;
  problem.residuals(c.fromZ(start, z), r);
  double cost = 0.5 * r.squaredNorm();
  double mu = 1e-3;
  Eigen::MatrixXd jac;
  for (int it = 0; it < max_iterations && z.size() > 0; ++it) {
    jacobian(problem, c, start, z, jac, pool);
    const Eigen::MatrixXd jtj = jac.transpose() * jac;
    const Eigen::VectorXd g = jac.transpose() * r;
    bool improved = false;
    for (int tries = 0; tries < 12; ++tries) {
      Eigen::MatrixXd a = jtj;
      for (Eigen::Index k = 0; k < a.rows(); ++k) a(k, k) += mu * std::max(jtj(k, k), 1e-12);
      const Eigen::VectorXd step = a.ldlt().solve(-g);
      const Eigen::VectorXd z_new = c.clamp(z + step);
      Eigen::VectorXd r_new;
      problem.residuals(c.fromZ(start, z_new), r_new);
      const double cost_new = 0.5 * r_new.squaredNorm();
      if (cost_new < cost) {
        const double gain = (cost - cost_new) / std::max(cost, 1e-300);
        const double moved = (z_new - z).norm();
        z = z_new;
        r = r_new;
        cost = cost_new;
        mu = std::max(mu / 3.0, 1e-12);
        improved = true;
        if (gain < 1e-12 || moved < 1e-12) it = max_iterations;
        break;
      }
      mu *= 4.0;
    }
    if (!improved) break;
  }
  Polished out;
  out.model = c.fromZ(start, z);
  out.cost = cost;
  jacobian(problem, c, start, z, jac, pool);
  out.jacobian = jac;
  return out;
}

}  // namespace

double valveLoadFlow(const GreyModel& m, double x_v, double tau_h_nm) noexcept {
  if (m.stall_torque_nm <= 0.0 && m.underlap_v <= 0.0 && m.edge_rounding_v <= 0.0) return x_v;
  // (I1) Q = r(x + l) sqrt(1 - tau_h / tau_s) - r(l - x) sqrt(1 + tau_h / tau_s).
  const double load = m.stall_torque_nm > 0.0 ? tau_h_nm / m.stall_torque_nm : 0.0;
  const double supply_side = std::sqrt(std::max(0.0, 1.0 - load));
  const double return_side = std::sqrt(std::max(0.0, 1.0 + load));
  return roundedOpening(x_v + m.underlap_v, m.edge_rounding_v) * supply_side -
         roundedOpening(m.underlap_v - x_v, m.edge_rounding_v) * return_side;
}

const char* greyParamName(int index) noexcept {
  switch (index) {
    case kFlowGain:
      return "flow_gain_radps_per_v";
    case kStiffness:
      return "hydraulic_stiffness_nm_per_rad";
    case kLeakage:
      return "leakage_radps_per_nm";
    case kInertia:
      return "inertia_kgm2";
    case kViscous:
      return "viscous_nms_per_rad";
    case kCoulomb:
      return "coulomb_nm";
    case kStribeck:
      return "stribeck_nm";
    case kLoadTorque:
      return "load_torque_nm";
    case kValveOffset:
      return "valve_offset_v";
    case kAngleOffset:
      return "angle_offset_rad";
    case kTorqueOffset:
      return "torque_offset_nm";
    default:
      return "unknown";
  }
}

ExperimentData experimentFromLog(const SignalTable& log) {
  ExperimentData d;
  const auto& t = log.column("time_s");
  if (t.size() < 3) throw std::invalid_argument("experiment log: fewer than three rows");
  for (const auto& column : log.columns) {
    for (std::size_t k = 0; k < column.size(); ++k) {
      if (!std::isfinite(column[k])) {
        throw std::invalid_argument("experiment log: a non-finite value at row " + std::to_string(k + 1));
      }
    }
  }
  d.sample_period_s = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
  for (std::size_t k = 1; k < t.size(); ++k) {
    if (std::abs(t[k] - t[k - 1] - d.sample_period_s) > 1e-6 * d.sample_period_s + 1e-9) {
      throw std::invalid_argument("experiment log: time step at row " + std::to_string(k + 1) + " is " +
                                  std::to_string(t[k] - t[k - 1]) + " s, the log's mean step is " +
                                  std::to_string(d.sample_period_s) + " s");
    }
  }
  d.excitation_v = log.column("excitation_v");
  d.command_v = log.column("command_v");
  d.q_rad = log.column("q_rad");
  d.tau_nm = log.column("tau_measured_nm");
  // u - r = K q_hold - K q: a straight line in q.
  const auto n = static_cast<double>(t.size());
  double sq = 0.0, sy = 0.0, sqq = 0.0, sqy = 0.0;
  for (std::size_t k = 0; k < t.size(); ++k) {
    const double y = d.command_v[k] - d.excitation_v[k];
    sq += d.q_rad[k];
    sy += y;
    sqq += d.q_rad[k] * d.q_rad[k];
    sqy += d.q_rad[k] * y;
  }
  const double var = sqq - sq * sq / n;
  if (!(var > 0.0)) throw std::invalid_argument("experiment log: the angle never moves, no hold law to recover");
  const double slope = (sqy - sq * sy / n) / var;
  if (!(slope < 0.0)) {
    throw std::invalid_argument("experiment log: command minus excitation does not fall with the angle (slope " +
                                std::to_string(slope) + " V/rad): no position hold in the log");
  }
  d.hold_gain_v_per_rad = -slope;
  d.hold_rad = (sy - slope * sq) / n / d.hold_gain_v_per_rad;
  return d;
}

Simulation simulateClosedLoop(const GreyModel& model, const ExperimentData& data) {
  const std::size_t n = data.q_rad.size();
  Simulation s;
  s.q_rad.resize(n);
  s.tau_nm.resize(n);
  s.command_v.resize(n);
  const auto& p = model.value;
  State x;
  x.q = n > 0 ? data.q_rad[0] - p[kAngleOffset] : 0.0;
  x.th = p[kLoadTorque];
  x.tf = p[kLoadTorque];
  // At rest the spool sits where the valve's flow balances the leakage under the static load.
  x.x = restingValve(model);
  const double q_ref = x.q;
  const std::size_t d = static_cast<std::size_t>(std::max(0, model.delay_samples));
  std::vector<double> out_q(n), out_tau(n);
  const int substeps = model.spool_hz > 0.0 ? 2 * kSubsteps : kSubsteps;
  const double h = data.sample_period_s / substeps;
  // (I1)-(I2) in closed loop: the hold law on the delayed reading, the command held over the sample.
  for (std::size_t k = 0; k < n; ++k) {
    out_q[k] = x.q + p[kAngleOffset];
    out_tau[k] = measuredTorque(model, x);
    const std::size_t seen = k >= d ? k - d : 0;
    s.q_rad[k] = out_q[seen];
    s.tau_nm[k] = out_tau[seen];
    const double u = data.hold_gain_v_per_rad * (data.hold_rad - s.q_rad[k]) + data.excitation_v[k];
    s.command_v[k] = u;
    for (int i = 0; i < substeps; ++i) x = rk4Step(model, x, u, q_ref, h);
    sampleLoadCell(model, x, data.sample_period_s);
    if (!std::isfinite(x.q) || !std::isfinite(x.w) || !std::isfinite(x.th) || std::abs(x.q) > 1e3) {
      s.ok = false;
      return s;
    }
  }
  return s;
}

namespace {

constexpr int kStates = 6;
using StateVector = Eigen::Matrix<double, kStates, 1>;
using StateMatrix = Eigen::Matrix<double, kStates, kStates>;

StateVector toVector(const State& x) {
  StateVector v;
  v << x.q, x.w, x.th, x.x, x.xd, x.tf;
  return v;
}

State fromVector(const StateVector& v) {
  return {v[0], v[1], v[2], v[3], v[4], v[5]};
}

// One sample of the reduced model under a held command (the simulation's RK4 sub-steps).
StateVector stepSample(const GreyModel& m, const StateVector& v, double u, double q_ref, double dt) {
  const int substeps = m.spool_hz > 0.0 ? 2 * kSubsteps : kSubsteps;
  const double h = dt / substeps;
  State x = fromVector(v);
  for (int i = 0; i < substeps; ++i) x = rk4Step(m, x, u, q_ref, h);
  sampleLoadCell(m, x, dt);
  return toVector(x);
}

Eigen::Vector2d readings(const GreyModel& m, const StateVector& v) {
  const State x = fromVector(v);
  return {x.q + m.value[kAngleOffset], measuredTorque(m, x)};
}

// Finite-difference step of each state: angle, speed, hydraulic torque, spool (V), spool rate, filtered torque.
constexpr std::array<double, kStates> kStateStep{1e-7, 1e-6, 1e-5, 1e-7, 1e-4, 1e-5};

}  // namespace

Simulation predictOneStep(const GreyModel& model, const ExperimentData& data, const PredictorNoise& noise) {
  if (!(noise.angle_rad > 0.0 && noise.torque_nm > 0.0 && noise.process_torque_nm > 0.0 &&
        noise.process_speed_radps > 0.0 && noise.torque_cell_nm >= 0.0)) {
    throw std::invalid_argument("one-step prediction: every noise level must be positive (the load cell's analog "
                                "noise non-negative)");
  }
  const std::size_t n = data.q_rad.size();
  Simulation s;
  s.q_rad.resize(n);
  s.tau_nm.resize(n);
  s.command_v.resize(n);
  if (n == 0) return s;
  const auto& p = model.value;
  // The simulation's initial state.
  State x0;
  x0.q = data.q_rad[0] - p[kAngleOffset];
  x0.th = p[kLoadTorque];
  x0.tf = p[kLoadTorque];
  x0.x = restingValve(model);
  const double q_ref = x0.q;
  StateVector x = toVector(x0);
  StateMatrix cov = StateMatrix::Zero();
  cov(0, 0) = noise.angle_rad * noise.angle_rad;
  cov(1, 1) = noise.process_speed_radps * noise.process_speed_radps;
  cov(2, 2) = noise.process_torque_nm * noise.process_torque_nm;
  if (model.torque_filter_hz > 0.0) cov(5, 5) = noise.torque_nm * noise.torque_nm;
  StateMatrix process = StateMatrix::Zero();
  process(1, 1) = noise.process_speed_radps * noise.process_speed_radps;
  process(2, 2) = noise.process_torque_nm * noise.process_torque_nm;
  double torque_reading_var = noise.torque_nm * noise.torque_nm;
  if (model.torque_filter_hz > 0.0) {
    // The analog noise, held over the sample, through the first-order filter.
    const double pass = 1.0 - std::exp(-2.0 * std::numbers::pi * model.torque_filter_hz * data.sample_period_s);
    process(5, 5) = pass * pass * noise.torque_cell_nm * noise.torque_cell_nm;
  } else {
    torque_reading_var += noise.torque_cell_nm * noise.torque_cell_nm;
  }
  const Eigen::Matrix2d r_meas =
      Eigen::Vector2d(noise.angle_rad * noise.angle_rad, torque_reading_var).asDiagonal();
  const std::size_t d = static_cast<std::size_t>(std::max(0, model.delay_samples));
  const Eigen::Vector2d first = readings(model, x);
  for (std::size_t j = 0; j < std::min(d, n); ++j) {
    s.q_rad[j] = first[0];
    s.tau_nm[j] = first[1];
  }
  // I9: the extended Kalman filter's predict-update cycle. State m is seen by reading m + d; the
  // command of sample m acts over [m, m + 1].
  for (std::size_t m = 0; m + d < n; ++m) {
    const std::size_t j = m + d;
    const Eigen::Vector2d predicted = readings(model, x);
    s.q_rad[j] = predicted[0];
    s.tau_nm[j] = predicted[1];
    // Update with reading j.
    Eigen::Matrix<double, 2, kStates> hm;
    for (int i = 0; i < kStates; ++i) {
      StateVector xp = x;
      xp[i] += kStateStep[static_cast<std::size_t>(i)];
      hm.col(i) = (readings(model, xp) - predicted) / kStateStep[static_cast<std::size_t>(i)];
    }
    const Eigen::Matrix2d innovation_cov = hm * cov * hm.transpose() + r_meas;
    const Eigen::Matrix<double, kStates, 2> gain = cov * hm.transpose() * innovation_cov.inverse();
    x += gain * (Eigen::Vector2d(data.q_rad[j], data.tau_nm[j]) - predicted);
    const StateMatrix a = StateMatrix::Identity() - gain * hm;
    cov = a * cov * a.transpose() + gain * r_meas * gain.transpose();  // Joseph form
    // Propagate over sample m with the command the hold law gave from reading m.
    const double u = data.hold_gain_v_per_rad * (data.hold_rad - data.q_rad[m]) + data.excitation_v[m];
    s.command_v[m] = u;
    const StateVector next = stepSample(model, x, u, q_ref, data.sample_period_s);
    StateMatrix f;
    for (int i = 0; i < kStates; ++i) {
      StateVector xp = x;
      xp[i] += kStateStep[static_cast<std::size_t>(i)];
      f.col(i) =
          (stepSample(model, xp, u, q_ref, data.sample_period_s) - next) / kStateStep[static_cast<std::size_t>(i)];
    }
    x = next;
    cov = f * cov * f.transpose() + process;
    if (!x.allFinite() || std::abs(x[0]) > 1e3) {
      s.ok = false;
      return s;
    }
  }
  return s;
}

FitOptions defaultFitOptions(const GreyModel& nominal, double factor) {
  FitOptions o;
  for (int i = 0; i < kGreyParams; ++i) {
    ParamSpec& s = o.params[static_cast<std::size_t>(i)];
    const double v = nominal.value[static_cast<std::size_t>(i)];
    if (i == kLoadTorque) {
      s = {true, v - 20.0, v + 20.0, false};
    } else if (i == kValveOffset || i == kAngleOffset || i == kTorqueOffset) {
      s = {false, v - 1.0, v + 1.0, false};
    } else if (v > 0.0) {
      s = {true, v / factor, v * factor, true};
    } else {
      s = {false, v, v, true};
    }
  }
  return o;
}

FitResult fitGreyModel(const std::vector<ExperimentData>& experiments, const GreyModel& start,
                       const FitOptions& options) {
  if (experiments.empty()) throw std::invalid_argument("grey-box fit: no experiments");
  for (int i = 0; i < kGreyParams; ++i) {
    const ParamSpec& s = options.params[static_cast<std::size_t>(i)];
    if (!s.free) continue;
    const double v = start.value[static_cast<std::size_t>(i)];
    if (s.log_scaled && !(s.min > 0.0)) {
      throw std::invalid_argument(std::string("grey-box fit: ") + greyParamName(i) +
                                  " is log-scaled and needs positive bounds, got min " + std::to_string(s.min));
    }
    if (!(s.min <= v && v <= s.max)) {
      throw std::invalid_argument(std::string("grey-box fit: start ") + greyParamName(i) + " = " + std::to_string(v) +
                                  " outside its bounds " + std::to_string(s.min) + ".." + std::to_string(s.max));
    }
  }
  const Coordinates c(options);
  Problem problem(experiments);
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  using Clock = std::chrono::steady_clock;

  // Global stage: the start and a seeded sample of the box, at every delay.
  const auto t0 = Clock::now();
  struct Candidate {
    double cost = kInf;
    GreyModel model;
  };
  core::JobPool pool(std::max(1, options.threads));
  const int samples = std::max(1, options.global_samples);
  const int delays = options.max_delay_samples + 1;
  std::vector<Candidate> candidates(static_cast<std::size_t>(samples * delays));
  constexpr int kBlock = 25;  // points per progress line
  for (int first = 0; first < samples; first += kBlock) {
    const int count = std::min(kBlock, samples - first);
    pool.run(count * delays, [&](int task) {
      const int sample = first + task / delays;
      Eigen::VectorXd z = c.toZ(start);
      if (sample > 0) {
        core::RandomStream rng(options.seed, 0x6772657962ULL, static_cast<std::uint64_t>(sample));
        for (Eigen::Index k = 0; k < z.size(); ++k) z[k] = rng.uniform(c.lo[k], c.hi[k]);
      }
      GreyModel m = c.fromZ(start, z);
      m.delay_samples = task % delays;
      const double cost = problem.cost(m);
      candidates[static_cast<std::size_t>(sample * delays + task % delays)] = {std::isfinite(cost) ? cost : kInf, m};
    });
    say("global stage: " + std::to_string(first + count) + "/" + std::to_string(samples) + " points x " +
        std::to_string(delays) + " delays");
  }
  // Ties keep the sampling order, so the result does not depend on the thread count.
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  FitResult result;
  result.global_seconds = std::chrono::duration<double>(Clock::now() - t0).count();

  // Polish the best candidates; then the delays next to the winner's.
  const auto t1 = Clock::now();
  Polished best;
  best.cost = std::numeric_limits<double>::infinity();
  const std::size_t count =
      std::min(candidates.size(), static_cast<std::size_t>(std::max(1, options.polished_candidates)));
  for (std::size_t i = 0; i < count; ++i) {
    Polished p = polish(problem, c, candidates[i].model, options.max_iterations, pool);
    std::ostringstream line;
    line << "polish " << i + 1 << "/" << count << ": delay " << p.model.delay_samples << " samples, cost "
         << candidates[i].cost << " -> " << p.cost;
    say(line.str());
    if (p.cost < best.cost) best = std::move(p);
  }
  for (int step : {-1, 1}) {
    GreyModel m = best.model;
    m.delay_samples += step;
    if (m.delay_samples < 0 || m.delay_samples > options.max_delay_samples) continue;
    Polished p = polish(problem, c, m, options.max_iterations, pool);
    say("delay " + std::to_string(m.delay_samples) + " samples: cost " + std::to_string(p.cost));
    if (p.cost < best.cost) best = std::move(p);
  }
  result.polish_seconds = std::chrono::duration<double>(Clock::now() - t1).count();

  result.model = best.model;
  result.cost = best.cost;
  result.evaluations = problem.evaluations.load();
  result.free_params = c.index;
  // Covariance of the fit coordinates: s^2 (J^T J)^+, s^2 the residual variance.
  const Eigen::Index np = best.jacobian.cols();
  result.correlation = Eigen::MatrixXd::Identity(np, np);
  if (np > 0) {
    const double dof = std::max<double>(1.0, static_cast<double>(problem.residualCount() - np));
    const double s2 = 2.0 * best.cost / dof;
    Eigen::VectorXd norms = best.jacobian.colwise().norm().transpose();
    for (Eigen::Index k = 0; k < np; ++k) norms[k] = norms[k] > 0.0 ? norms[k] : 1.0;
    const Eigen::MatrixXd scaled = best.jacobian * norms.cwiseInverse().asDiagonal();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(scaled, Eigen::ComputeThinV);
    const Eigen::VectorXd sv = svd.singularValues();
    const double smax = sv.size() > 0 ? sv[0] : 0.0;
    constexpr double kRankTolerance = 1e-6;
    Eigen::MatrixXd cov_scaled = Eigen::MatrixXd::Zero(np, np);
    for (Eigen::Index k = 0; k < sv.size(); ++k) {
      if (sv[k] > kRankTolerance * smax) {
        cov_scaled += svd.matrixV().col(k) * svd.matrixV().col(k).transpose() / (sv[k] * sv[k]);
      } else {
        std::string direction;
        for (Eigen::Index j = 0; j < np; ++j) {
          const double weight = svd.matrixV()(j, k);
          if (std::abs(weight) < 0.2) continue;
          std::ostringstream term;
          term.precision(2);
          term << (direction.empty() ? "" : (weight > 0 ? " + " : " - "))
               << (direction.empty() && weight < 0 ? "-" : "") << std::abs(weight) << " "
               << greyParamName(c.index[static_cast<std::size_t>(j)]);
          direction += term.str();
        }
        result.unidentifiable.push_back(direction);
      }
    }
    const Eigen::MatrixXd cov = s2 * norms.cwiseInverse().asDiagonal() * cov_scaled * norms.cwiseInverse().asDiagonal();
    for (Eigen::Index k = 0; k < np; ++k) {
      const auto i = static_cast<std::size_t>(c.index[static_cast<std::size_t>(k)]);
      const double sd = std::sqrt(std::max(0.0, cov(k, k)));
      result.standard_error[i] = c.log_scaled[static_cast<std::size_t>(k)] ? sd * result.model.value[i] : sd;
      for (Eigen::Index j = 0; j < np; ++j) {
        const double denom = std::sqrt(cov(k, k) * cov(j, j));
        result.correlation(k, j) = denom > 0.0 ? cov(k, j) / denom : (k == j ? 1.0 : 0.0);
      }
    }
  }
  return result;
}

double fitPercent(const std::vector<double>& measured, const std::vector<double>& modelled) {
  if (measured.size() != modelled.size() || measured.empty()) {
    throw std::invalid_argument("fit percentage: " + std::to_string(measured.size()) + " measured and " +
                                std::to_string(modelled.size()) + " modelled samples");
  }
  // I6: fit = 100 (1 - |y - y_hat| / |y - mean(y)|).
  double mean = 0.0;
  for (double v : measured) mean += v;
  mean /= static_cast<double>(measured.size());
  double err = 0.0, dev = 0.0;
  for (std::size_t k = 0; k < measured.size(); ++k) {
    err += (measured[k] - modelled[k]) * (measured[k] - modelled[k]);
    dev += (measured[k] - mean) * (measured[k] - mean);
  }
  if (!(dev > 0.0)) throw std::invalid_argument("fit percentage: the measured signal is constant");
  return 100.0 * (1.0 - std::sqrt(err / dev));
}

}  // namespace fullarm::identification
