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
#include <string>
#include <type_traits>
#include <utility>

#include "fullarm/core/job_pool.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::identification {
namespace {

constexpr int kSubsteps = 4;
constexpr double kDivergedResidual = 1.0e3;
constexpr double kInf = std::numeric_limits<double>::infinity();

// Forward-mode dual number: a value and its derivatives along N directions (the fitted parameters
// seeded one per direction). The simulation is templated on its scalar, so one run in Dual
// carries the exact derivatives of the discretised simulation (every RK4 sub-step, the hold law
// and the delay line) alongside its values (I10).
constexpr int kDirections = 4;  // directions per sensitivity run (a SIMD-friendly width)

template <int N>
struct Dual {
  double v = 0.0;
  std::array<double, N> d{};
  Dual() = default;
  Dual(double value) : v(value) {}  // NOLINT(google-explicit-constructor): constants mix freely
};

template <int N>
Dual<N> operator+(const Dual<N>& a, const Dual<N>& b) {
  Dual<N> r(a.v + b.v);
  for (int i = 0; i < N; ++i) r.d[i] = a.d[i] + b.d[i];
  return r;
}
template <int N>
Dual<N> operator-(const Dual<N>& a, const Dual<N>& b) {
  Dual<N> r(a.v - b.v);
  for (int i = 0; i < N; ++i) r.d[i] = a.d[i] - b.d[i];
  return r;
}
template <int N>
Dual<N> operator-(const Dual<N>& a) {
  Dual<N> r(-a.v);
  for (int i = 0; i < N; ++i) r.d[i] = -a.d[i];
  return r;
}
template <int N>
Dual<N> operator*(const Dual<N>& a, const Dual<N>& b) {
  Dual<N> r(a.v * b.v);
  for (int i = 0; i < N; ++i) r.d[i] = a.d[i] * b.v + a.v * b.d[i];
  return r;
}
template <int N>
Dual<N> operator/(const Dual<N>& a, const Dual<N>& b) {
  const double inv = 1.0 / b.v;
  Dual<N> r(a.v / b.v);
  for (int i = 0; i < N; ++i) r.d[i] = (a.d[i] - r.v * b.d[i]) * inv;
  return r;
}
template <int N>
Dual<N> operator+(const Dual<N>& a, double b) {
  Dual<N> r = a;
  r.v += b;
  return r;
}
template <int N>
Dual<N> operator+(double a, const Dual<N>& b) {
  return b + a;
}
template <int N>
Dual<N> operator-(const Dual<N>& a, double b) {
  Dual<N> r = a;
  r.v -= b;
  return r;
}
template <int N>
Dual<N> operator-(double a, const Dual<N>& b) {
  Dual<N> r = -b;
  r.v += a;
  return r;
}
template <int N>
Dual<N> operator*(const Dual<N>& a, double b) {
  Dual<N> r(a.v * b);
  for (int i = 0; i < N; ++i) r.d[i] = a.d[i] * b;
  return r;
}
template <int N>
Dual<N> operator*(double a, const Dual<N>& b) {
  return b * a;
}
template <int N>
Dual<N> operator/(const Dual<N>& a, double b) {
  return a * (1.0 / b);
}
// The chain rule through the elementary functions: f(a) with f'(a) along every direction.
template <int N>
Dual<N> chain(const Dual<N>& a, double f, double df) {
  Dual<N> r(f);
  for (int i = 0; i < N; ++i) r.d[i] = df * a.d[i];
  return r;
}
template <int N>
Dual<N> exp(const Dual<N>& a) {
  const double e = std::exp(a.v);
  return chain(a, e, e);
}
template <int N>
Dual<N> tanh(const Dual<N>& a) {
  const double t = std::tanh(a.v);
  return chain(a, t, 1.0 - t * t);
}
template <int N>
Dual<N> sqrt(const Dual<N>& a) {
  const double s = std::sqrt(a.v);
  return chain(a, s, 0.5 / s);
}

using Sens = Dual<kDirections>;

inline double valueOf(double x) noexcept {
  return x;
}
template <int N>
double valueOf(const Dual<N>& x) noexcept {
  return x.v;
}

template <class T>
using Values = std::array<T, kGreyParams>;

template <class T>
struct StateT {
  T q{}, w{}, th{};
  T x{}, xd{};  // spool position (in volts of command) and its rate
  T tf{};       // filtered load-cell torque
};
using State = StateT<double>;

// Edge opening rounded over w (the plant's H2 in volts): 0 below -w, s above w, a quadratic blend
// between (continuously differentiable, so its sensitivity is exact everywhere).
template <class T>
T roundedOpening(const T& s, double w) noexcept {
  if (w <= 0.0) return valueOf(s) > 0.0 ? s : T(0.0);
  if (valueOf(s) <= -w) return T(0.0);
  if (valueOf(s) >= w) return s;
  return (s + w) * (s + w) / (4.0 * w);
}

// sqrt(max(0, a)): a pressure drop that would reverse gives no flow; past that point the flow
// no longer depends on the load, so its derivative there is zero (one-sided).
template <class T>
T clampedSqrt(const T& a) noexcept {
  using std::sqrt;
  if constexpr (std::is_same_v<T, double>) {
    return std::sqrt(std::max(0.0, a));
  } else {
    return valueOf(a) > 0.0 ? sqrt(a) : T(0.0);
  }
}

// (I1)'s Q(x, tau_h).
template <class T>
T loadFlow(const GreyModel& m, const T& x_v, const T& tau_h_nm) noexcept {
  if (m.stall_torque_nm <= 0.0 && m.underlap_v <= 0.0 && m.edge_rounding_v <= 0.0) return x_v;
  // (I1) Q = r(x + l) sqrt(1 - tau_h / tau_s) - r(l - x) sqrt(1 + tau_h / tau_s).
  const T load = m.stall_torque_nm > 0.0 ? tau_h_nm / m.stall_torque_nm : T(0.0);
  const T supply_side = clampedSqrt(1.0 - load);
  const T return_side = clampedSqrt(1.0 + load);
  return roundedOpening(x_v + m.underlap_v, m.edge_rounding_v) * supply_side -
         roundedOpening(m.underlap_v - x_v, m.edge_rounding_v) * return_side;
}

// Friction f(w) of (I2): Coulomb and Stribeck level with a tanh-smoothed sign, plus viscous.
template <class T>
T friction(const GreyModel& m, const Values<T>& p, const T& w) noexcept {
  using std::exp;
  using std::tanh;
  const T r = w / m.stribeck_velocity_radps;
  const T level = p[kCoulomb] + p[kStribeck] * exp(-r * r);
  return level * tanh(w / m.coulomb_smoothing_radps) + p[kViscous] * w;
}

// The reduced joint's right-hand side, (I1)-(I2) of grey_box.hpp.
template <class T>
T cellTorque(const GreyModel& m, const Values<T>& p, const StateT<T>& x) noexcept {
  return x.th - friction(m, p, x.w);
}

template <class T>
StateT<T> rhs(const GreyModel& m, const Values<T>& p, const StateT<T>& x, const T& u, const T& q_ref) noexcept {
  StateT<T> d;
  T drive = u;
  if (m.spool_hz > 0.0) {
    const double wn = 2.0 * std::numbers::pi * m.spool_hz;
    d.x = x.xd;
    d.xd = wn * wn * (u - x.x) - 2.0 * m.spool_damping * wn * x.xd;
    drive = x.x;
  }
  d.q = x.w;
  d.w = (cellTorque(m, p, x) - p[kLoadTorque] - m.load_gradient_nm_per_rad * (x.q - q_ref)) / p[kInertia];
  d.th = p[kStiffness] * (p[kFlowGain] * loadFlow(m, drive + p[kValveOffset], x.th) - x.w - p[kLeakage] * x.th);
  return d;  // d.tf = 0: the load-cell filter acts on the samples (sampleLoadCell)
}

// The load cell's first-order filter on the sampled torque, as the plant's sensor model has it
// (exact ZOH discretisation, the new sample held over the period it closes):
// tf_k = a tf_{k-1} + (1 - a) tau_cell(t_k), a = exp(-2 pi f_c T).
template <class T>
void sampleLoadCell(const GreyModel& m, const Values<T>& p, StateT<T>& x, double dt) noexcept {
  if (m.torque_filter_hz <= 0.0) return;
  const double a = std::exp(-2.0 * std::numbers::pi * m.torque_filter_hz * dt);
  x.tf = a * x.tf + (1.0 - a) * cellTorque(m, p, x);
}

// The spool position (before the offset) where the valve's flow feeds the initial motion and the
// leakage: a Q(x + u_0, tau_h0) = w_0 + c tau_h0 (at rest, the flow balancing the leakage under the
// static load), by bisection (Q rises with x). Its sensitivity is the implicit function's,
// dx = -(dF at fixed x) / (dF/dx), from one Newton correction in dual arithmetic at the root.
template <class T>
T initialValve(const GreyModel& m, const Values<T>& p, const T& speed, const T& th0) noexcept {
  const T target = (speed + p[kLeakage] * th0) / p[kFlowGain];
  double lo = -100.0, hi = 100.0;
  for (int i = 0; i < 80; ++i) {
    const double mid = 0.5 * (lo + hi);
    (loadFlow(m, mid, valueOf(th0)) < valueOf(target) ? lo : hi) = mid;
  }
  const double root = 0.5 * (lo + hi);
  if constexpr (std::is_same_v<T, double>) {
    return root - p[kValveOffset];
  } else {
    T probe(root);
    probe.d[0] = 1.0;
    const double slope = loadFlow(m, probe, T(valueOf(th0))).d[0];
    const T residual = loadFlow(m, T(root), th0) - target;
    T y(root);
    if (slope > 0.0) {
      for (std::size_t i = 0; i < y.d.size(); ++i) y.d[i] = -residual.d[i] / slope;
    }
    return y - p[kValveOffset];
  }
}

template <class T>
StateT<T> axpy(const StateT<T>& x, double h, const StateT<T>& d) noexcept {
  return {x.q + h * d.q, x.w + h * d.w, x.th + h * d.th, x.x + h * d.x, x.xd + h * d.xd, x.tf + h * d.tf};
}

// One classical RK4 step of length h under the held command u.
template <class T>
StateT<T> rk4Step(const GreyModel& m, const Values<T>& p, const StateT<T>& x, const T& u, const T& q_ref,
                  double h) noexcept {
  const StateT<T> k1 = rhs(m, p, x, u, q_ref);
  const StateT<T> k2 = rhs(m, p, axpy(x, 0.5 * h, k1), u, q_ref);
  const StateT<T> k3 = rhs(m, p, axpy(x, 0.5 * h, k2), u, q_ref);
  const StateT<T> k4 = rhs(m, p, axpy(x, h, k3), u, q_ref);
  return axpy(axpy(axpy(axpy(x, h / 6.0, k1), h / 3.0, k2), h / 3.0, k3), h / 6.0, k4);
}

template <class T>
T measuredTorque(const GreyModel& m, const Values<T>& p, const StateT<T>& x) noexcept {
  return (m.torque_filter_hz > 0.0 ? x.tf : cellTorque(m, p, x)) + p[kTorqueOffset];
}

// The simulation's initial state: the first logged angle, the given speed and hydraulic torque
// tau_g + the torque offset, the load-cell filter settled on the torque the cell then sees and
// the spool at rest where its flow feeds that motion (initialValve).
template <class T>
StateT<T> initialState(const GreyModel& m, const Values<T>& p, double first_angle_rad, const T& speed,
                       const T& torque_offset) noexcept {
  StateT<T> x;
  x.q = first_angle_rad - p[kAngleOffset];
  x.w = speed;
  x.th = p[kLoadTorque] + torque_offset;
  x.tf = cellTorque(m, p, x);
  x.x = initialValve(m, p, speed, x.th);
  return x;
}

// The closed loop of simulateClosedLoop in scalar T.
template <class T>
struct Trajectory {
  std::vector<T> q_rad, tau_nm, tau_hydraulic_nm;
  std::vector<double> command_v;
  bool ok = true;
};

template <class T>
Trajectory<T> simulate(const GreyModel& model, const Values<T>& p, const ExperimentData& data, const T& speed,
                       const T& torque_offset) {
  const std::size_t n = data.q_rad.size();
  Trajectory<T> s;
  s.q_rad.resize(n);
  s.tau_nm.resize(n);
  s.tau_hydraulic_nm.resize(n);
  s.command_v.resize(n);
  const std::size_t d = static_cast<std::size_t>(std::max(0, model.delay_samples));
  // The first state is the one reading d shows (the readings before it show earlier states,
  // which the simulation takes as the first: at rest they are the same).
  StateT<T> x =
      initialState(model, p, n > 0 ? data.q_rad[std::min(d, n - 1)] : valueOf(p[kAngleOffset]), speed, torque_offset);
  const T q_ref = x.q;
  std::vector<T> out_q(n), out_tau(n), out_hydraulic(n);
  const int substeps = model.spool_hz > 0.0 ? 2 * kSubsteps : kSubsteps;
  const double h = data.sample_period_s / substeps;
  // (I1)-(I2) in closed loop: the hold law on the delayed reading, the command held over the
  // sample. The delay is an integer number of samples and is not differentiated.
  for (std::size_t k = 0; k < n; ++k) {
    out_q[k] = x.q + p[kAngleOffset];
    out_tau[k] = measuredTorque(model, p, x);
    out_hydraulic[k] = x.th;
    if (k >= d) {
      s.q_rad[k] = out_q[k - d];
      s.tau_nm[k] = out_tau[k - d];
      s.tau_hydraulic_nm[k] = out_hydraulic[k - d];
    } else {
      // The first d readings show states from before the first one, which the simulation does
      // not model: they are taken as logged (at rest, the first state's readings), and so is
      // the command the hold law computed from them (a log without torques: the first state's).
      s.q_rad[k] = T(data.q_rad[k]);
      s.tau_nm[k] = data.tau_nm.size() == n ? T(data.tau_nm[k]) : out_tau[0];
      s.tau_hydraulic_nm[k] = data.tau_hydraulic_nm.size() == n ? T(data.tau_hydraulic_nm[k]) : out_hydraulic[0];
    }
    const T u = data.hold_gain_v_per_rad * (data.hold_rad - s.q_rad[k]) + data.excitation_v[k];
    s.command_v[k] = valueOf(u);
    for (int i = 0; i < substeps; ++i) x = rk4Step(model, p, x, u, q_ref, h);
    sampleLoadCell(model, p, x, data.sample_period_s);
    if (!std::isfinite(valueOf(x.q)) || !std::isfinite(valueOf(x.w)) || !std::isfinite(valueOf(x.th)) ||
        std::abs(valueOf(x.q)) > 1e3) {
      s.ok = false;
      return s;
    }
  }
  return s;
}

// The sensitivities of one run along up to kDirections parameters (GreyParam indices or
// kInitialSpeed / kInitialTorqueOffset; -1 pads an unused direction).
Trajectory<Sens> simulateDirections(const GreyModel& model, const ExperimentData& data, const InitialState& initial,
                                    const std::array<int, kDirections>& directions) {
  Values<Sens> p;
  for (int i = 0; i < kGreyParams; ++i) p[static_cast<std::size_t>(i)] = Sens(model.value[static_cast<std::size_t>(i)]);
  Sens speed(initial.speed_radps), torque(initial.torque_offset_nm);
  for (std::size_t j = 0; j < directions.size(); ++j) {
    const int i = directions[j];
    if (i >= 0 && i < kGreyParams) {
      p[static_cast<std::size_t>(i)].d[j] = 1.0;
    } else if (i == kInitialSpeed) {
      speed.d[j] = 1.0;
    } else if (i == kInitialTorqueOffset) {
      torque.d[j] = 1.0;
    }
  }
  return simulate(model, p, data, speed, torque);
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

/// A point of the fit: the model and each experiment's initial state.
struct Point {
  GreyModel model;
  std::vector<InitialState> initial;
};

double& initialMember(InitialState& s, int direction) noexcept {
  return direction == kInitialSpeed ? s.speed_radps : s.torque_offset_nm;
}

/// The free parameters in fit coordinates (log for log-scaled ones): the model's groups first,
/// then each experiment's free initial states.
struct Coordinates {
  struct Slot {
    int param = 0;        ///< GreyParam index, or kInitialSpeed / kInitialTorqueOffset
    int experiment = -1;  ///< the initial state's experiment (-1 for the model's groups)
  };
  std::vector<Slot> slots;
  std::vector<int> index;  ///< GreyParam indices of the model's free groups
  std::vector<bool> log_scaled;
  Eigen::VectorXd lo, hi;
  Eigen::Index model_count = 0;

  Coordinates(const FitOptions& o, std::size_t experiments) {
    std::vector<const ParamSpec*> specs;
    for (int i = 0; i < kGreyParams; ++i) {
      const ParamSpec& s = o.params[static_cast<std::size_t>(i)];
      if (!s.free) continue;
      index.push_back(i);
      slots.push_back({i, -1});
      specs.push_back(&s);
    }
    model_count = static_cast<Eigen::Index>(slots.size());
    for (std::size_t e = 0; e < experiments; ++e) {
      if (o.initial_speed.free) {
        slots.push_back({kInitialSpeed, static_cast<int>(e)});
        specs.push_back(&o.initial_speed);
      }
      if (o.initial_torque_offset.free) {
        slots.push_back({kInitialTorqueOffset, static_cast<int>(e)});
        specs.push_back(&o.initial_torque_offset);
      }
    }
    const auto n = static_cast<Eigen::Index>(slots.size());
    lo.resize(n);
    hi.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const ParamSpec& s = *specs[static_cast<std::size_t>(k)];
      log_scaled.push_back(k < model_count && s.log_scaled);
      lo[k] = log_scaled.back() ? std::log(s.min) : s.min;
      hi[k] = log_scaled.back() ? std::log(s.max) : s.max;
    }
  }
  [[nodiscard]] Eigen::Index size() const noexcept { return static_cast<Eigen::Index>(slots.size()); }
  [[nodiscard]] double value(const Point& p, Eigen::Index k) const {
    const Slot& s = slots[static_cast<std::size_t>(k)];
    if (s.experiment < 0) return p.model.value[static_cast<std::size_t>(s.param)];
    InitialState copy = p.initial[static_cast<std::size_t>(s.experiment)];
    return initialMember(copy, s.param);
  }
  [[nodiscard]] Eigen::VectorXd toZ(const Point& p) const {
    Eigen::VectorXd z(size());
    for (Eigen::Index k = 0; k < size(); ++k) {
      const double v = value(p, k);
      z[k] = log_scaled[static_cast<std::size_t>(k)] ? std::log(v) : v;
    }
    return z;
  }
  /// Only the model's groups (the first model_count entries of z) are read.
  [[nodiscard]] GreyModel modelFromZ(const GreyModel& base, const Eigen::VectorXd& z) const {
    GreyModel m = base;
    for (Eigen::Index k = 0; k < model_count; ++k) {
      const double v = z[k];
      m.value[static_cast<std::size_t>(slots[static_cast<std::size_t>(k)].param)] =
          log_scaled[static_cast<std::size_t>(k)] ? std::exp(v) : v;
    }
    return m;
  }
  [[nodiscard]] Point fromZ(const Point& base, const Eigen::VectorXd& z) const {
    Point p = base;
    p.model = modelFromZ(base.model, z);
    for (Eigen::Index k = model_count; k < size(); ++k) {
      const Slot& s = slots[static_cast<std::size_t>(k)];
      initialMember(p.initial[static_cast<std::size_t>(s.experiment)], s.param) = z[k];
    }
    return p;
  }
  /// d(parameter)/d(coordinate) at the point: the value for a log-scaled one, else 1.
  [[nodiscard]] double chainFactor(const Point& p, Eigen::Index k) const {
    return log_scaled[static_cast<std::size_t>(k)] ? value(p, k) : 1.0;
  }
  [[nodiscard]] std::string name(Eigen::Index k) const {
    const Slot& s = slots[static_cast<std::size_t>(k)];
    if (s.experiment < 0) return greyParamName(s.param);
    return std::string(initialStateName(s.param)) + " of experiment " + std::to_string(s.experiment + 1);
  }
  [[nodiscard]] Eigen::VectorXd clamp(const Eigen::VectorXd& z) const { return z.cwiseMax(lo).cwiseMin(hi); }
};

// (I12) The gap between the hydraulic torque and the load cell's reading: the friction, as the
// load cell's filter and offset show it. The fit compares it, simulated against logged, as the
// third channel where the log has the chamber pressures.
std::vector<double> frictionGap(const ExperimentData& e) {
  std::vector<double> g(e.q_rad.size());
  for (std::size_t k = 0; k < g.size(); ++k) g[k] = e.tau_hydraulic_nm[k] - e.tau_nm[k];
  return g;
}

class Problem {
 public:
  /// Residuals from reading `first` of each experiment on: the first d readings of a simulation
  /// with a delay of d samples are taken as logged (no residual), so every delay up to the
  /// largest tried is judged over the same readings, and a longer delay does not win by leaving
  /// readings out.
  Problem(const std::vector<ExperimentData>& experiments, int first) : experiments_(experiments) {
    for (const auto& e : experiments_) {
      q_scale_.push_back(spread(e.q_rad));
      tau_scale_.push_back(spread(e.tau_nm));
      const bool hydraulic = !e.tau_hydraulic_nm.empty();  // its length checked by fitGreyModel
      hydraulic_scale_.push_back(hydraulic ? spread(frictionGap(e)) : 0.0);
      channels_.push_back(hydraulic ? 3 : 2);
      offset_.push_back(residual_count_);
      first_.push_back(std::min(static_cast<std::size_t>(std::max(0, first)), e.q_rad.size()));
      residual_count_ += channels_.back() * static_cast<Eigen::Index>(e.q_rad.size() - first_.back());
    }
  }
  [[nodiscard]] Eigen::Index residualCount() const noexcept { return residual_count_; }
  [[nodiscard]] std::size_t experimentCount() const noexcept { return experiments_.size(); }
  [[nodiscard]] const ExperimentData& experiment(std::size_t e) const { return experiments_[e]; }
  std::atomic<int> evaluations{0};
  std::atomic<int> sensitivity_evaluations{0};

  /// Thread-safe: each call simulates on its own.
  void residuals(const Point& pt, Eigen::VectorXd& r) {
    ++evaluations;
    r.resize(residual_count_);
    Eigen::Index at = 0;
    for (std::size_t e = 0; e < experiments_.size(); ++e) {
      const ExperimentData& x = experiments_[e];
      const Simulation s = simulateClosedLoop(pt.model, x, pt.initial[e]);
      for (std::size_t k = first_[e]; k < x.q_rad.size(); ++k) {
        const double rq = (s.q_rad[k] - x.q_rad[k]) / q_scale_[e];
        const double rt = (s.tau_nm[k] - x.tau_nm[k]) / tau_scale_[e];
        r[at++] = s.ok && std::isfinite(rq) ? rq : kDivergedResidual;
        r[at++] = s.ok && std::isfinite(rt) ? rt : kDivergedResidual;
        if (channels_[e] == 3) {
          const double rh =
              ((s.tau_hydraulic_nm[k] - s.tau_nm[k]) - (x.tau_hydraulic_nm[k] - x.tau_nm[k])) / hydraulic_scale_[e];
          r[at++] = s.ok && std::isfinite(rh) ? rh : kDivergedResidual;
        }
      }
    }
  }
  double cost(const Point& pt) {
    Eigen::VectorXd r;
    residuals(pt, r);
    return 0.5 * r.squaredNorm();
  }

  /// The rows of experiment e's residuals in column `col` of jac, from one sensitivity run's
  /// direction j scaled by `factor` (the coordinate's chain factor). Diverged or non-finite
  /// residuals are constants (kDivergedResidual) and have zero derivative.
  void fillColumn(std::size_t e, const Trajectory<Sens>& s, std::size_t j, double factor, Eigen::Index col,
                  Eigen::MatrixXd& jac) const {
    const ExperimentData& x = experiments_[e];
    Eigen::Index at = offset_[e];
    for (std::size_t k = first_[e]; k < x.q_rad.size(); ++k) {
      const double rq = (s.q_rad[k].v - x.q_rad[k]) / q_scale_[e];
      const double rt = (s.tau_nm[k].v - x.tau_nm[k]) / tau_scale_[e];
      jac(at++, col) = s.ok && std::isfinite(rq) ? s.q_rad[k].d[j] * factor / q_scale_[e] : 0.0;
      jac(at++, col) = s.ok && std::isfinite(rt) ? s.tau_nm[k].d[j] * factor / tau_scale_[e] : 0.0;
      if (channels_[e] == 3) {
        const double rh =
            ((s.tau_hydraulic_nm[k].v - s.tau_nm[k].v) - (x.tau_hydraulic_nm[k] - x.tau_nm[k])) / hydraulic_scale_[e];
        jac(at++, col) = s.ok && std::isfinite(rh)
                             ? (s.tau_hydraulic_nm[k].d[j] - s.tau_nm[k].d[j]) * factor / hydraulic_scale_[e]
                             : 0.0;
      }
    }
  }

 private:
  const std::vector<ExperimentData>& experiments_;
  std::vector<double> q_scale_, tau_scale_, hydraulic_scale_;
  std::vector<Eigen::Index> channels_;  // 2: angle and load cell; 3: and the hydraulic torque
  std::vector<Eigen::Index> offset_;
  std::vector<std::size_t> first_;
  Eigen::Index residual_count_ = 0;
};

struct Polished {
  Point point;
  double cost = 0.0;
  Eigen::MatrixXd jacobian;
};

// Central differences, the 2 p simulations spread over the pool.
void centralDifferenceJacobian(Problem& problem, const Coordinates& c, const Point& base, const Eigen::VectorXd& z,
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

// Forward sensitivities: per experiment, its coordinates (the model's groups and its own initial
// states) in runs of kDirections, the runs spread over the pool. The split depends only on the
// problem, so the Jacobian does not depend on the thread count.
void sensitivityJacobian(Problem& problem, const Coordinates& c, const Point& base, const Eigen::VectorXd& z,
                         Eigen::MatrixXd& jac, core::JobPool& pool) {
  const Point at = c.fromZ(base, z);
  jac.setZero(problem.residualCount(), z.size());
  struct Run {
    std::size_t experiment;
    std::vector<Eigen::Index> columns;
  };
  std::vector<Run> runs;
  for (std::size_t e = 0; e < problem.experimentCount(); ++e) {
    std::vector<Eigen::Index> columns;
    for (Eigen::Index k = 0; k < c.size(); ++k) {
      const int owner = c.slots[static_cast<std::size_t>(k)].experiment;
      if (owner < 0 || owner == static_cast<int>(e)) columns.push_back(k);
    }
    for (std::size_t first = 0; first < columns.size(); first += kDirections) {
      const std::size_t last = std::min(columns.size(), first + kDirections);
      runs.push_back({e, std::vector<Eigen::Index>(columns.begin() + static_cast<std::ptrdiff_t>(first),
                                                   columns.begin() + static_cast<std::ptrdiff_t>(last))});
    }
  }
  pool.run(static_cast<int>(runs.size()), [&](int task) {
    const Run& run = runs[static_cast<std::size_t>(task)];
    std::array<int, kDirections> directions{};
    directions.fill(-1);
    for (std::size_t j = 0; j < run.columns.size(); ++j) {
      directions[j] = c.slots[static_cast<std::size_t>(run.columns[j])].param;
    }
    ++problem.sensitivity_evaluations;
    const Trajectory<Sens> s =
        simulateDirections(at.model, problem.experiment(run.experiment), at.initial[run.experiment], directions);
    for (std::size_t j = 0; j < run.columns.size(); ++j) {
      problem.fillColumn(run.experiment, s, j, c.chainFactor(at, run.columns[j]), run.columns[j], jac);
    }
  });
}

void jacobian(JacobianMethod method, Problem& problem, const Coordinates& c, const Point& base,
              const Eigen::VectorXd& z, Eigen::MatrixXd& jac, core::JobPool& pool) {
  if (method == JacobianMethod::kCentralDifferences) {
    centralDifferenceJacobian(problem, c, base, z, jac, pool);
  } else {
    sensitivityJacobian(problem, c, base, z, jac, pool);
  }
}

// Projected Levenberg-Marquardt (Marquardt's diagonal scaling) inside the box. A coordinate on a
// bound whose gradient points out of the box is held there for the step (the active set), so the
// others move as the constrained problem asks rather than along a clipped unconstrained step.
Polished polish(Problem& problem, const Coordinates& c, const Point& start, int max_iterations, JacobianMethod method,
                core::JobPool& pool) {
  Eigen::VectorXd z = c.clamp(c.toZ(start));
  Eigen::VectorXd r;
  problem.residuals(c.fromZ(start, z), r);
  double cost = 0.5 * r.squaredNorm();
  double mu = 1e-3;
  Eigen::MatrixXd jac;
  for (int it = 0; it < max_iterations && z.size() > 0; ++it) {
    jacobian(method, problem, c, start, z, jac, pool);
    const Eigen::MatrixXd jtj = jac.transpose() * jac;
    const Eigen::VectorXd g = jac.transpose() * r;
    std::vector<bool> held(static_cast<std::size_t>(z.size()), false);
    for (Eigen::Index k = 0; k < z.size(); ++k) {
      held[static_cast<std::size_t>(k)] = (z[k] <= c.lo[k] && g[k] > 0.0) || (z[k] >= c.hi[k] && g[k] < 0.0);
    }
    bool improved = false;
    for (int tries = 0; tries < 12; ++tries) {
      Eigen::MatrixXd a = jtj;
      Eigen::VectorXd rhs = -g;
      for (Eigen::Index k = 0; k < a.rows(); ++k) {
        a(k, k) += mu * std::max(jtj(k, k), 1e-12);
        if (held[static_cast<std::size_t>(k)]) {
          a.row(k).setZero();
          a.col(k).setZero();
          a(k, k) = 1.0;
          rhs[k] = 0.0;
        }
      }
      const Eigen::VectorXd step = a.ldlt().solve(rhs);
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
  out.point = c.fromZ(start, z);
  out.cost = cost;
  jacobian(method, problem, c, start, z, jac, pool);
  out.jacobian = jac;
  return out;
}

// A free initial state's start from the data (fitGreyModel's documentation), clamped into its
// bounds; a fixed one at rest.
InitialState initialStateFromData(const GreyModel& m, const ExperimentData& d, const FitOptions& o) {
  InitialState s;
  // Reading `first` shows the simulation's first state.
  const std::size_t first =
      std::min(static_cast<std::size_t>(std::max(0, m.delay_samples)), d.q_rad.empty() ? 0 : d.q_rad.size() - 1);
  const std::size_t n = std::min<std::size_t>(d.q_rad.size() - first, 10);
  if (o.initial_speed.free && n >= 2) {
    double st = 0.0, sq = 0.0, stt = 0.0, stq = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const double t = static_cast<double>(k) * d.sample_period_s;
      st += t;
      sq += d.q_rad[first + k];
      stt += t * t;
      stq += t * d.q_rad[first + k];
    }
    const double nn = static_cast<double>(n);
    const double slope = (stq - st * sq / nn) / (stt - st * st / nn);
    s.speed_radps = std::clamp(slope, o.initial_speed.min, o.initial_speed.max);
  }
  if (o.initial_torque_offset.free && !d.tau_nm.empty()) {
    // tau_meas = tau_h - f(w) + tau_off at the first reading.
    const double th0 = d.tau_nm[first] - m.value[kTorqueOffset] + friction(m, m.value, s.speed_radps);
    s.torque_offset_nm =
        std::clamp(th0 - m.value[kLoadTorque], o.initial_torque_offset.min, o.initial_torque_offset.max);
  }
  return s;
}

Point pointFromData(const GreyModel& m, const std::vector<ExperimentData>& experiments, const FitOptions& o) {
  Point p{m, {}};
  for (const auto& e : experiments) p.initial.push_back(initialStateFromData(m, e, o));
  return p;
}

}  // namespace

double valveLoadFlow(const GreyModel& m, double x_v, double tau_h_nm) noexcept {
  // (I1) Q = r(x + l) sqrt(1 - tau_h / tau_s) - r(l - x) sqrt(1 + tau_h / tau_s), in doubles.
  return loadFlow(m, x_v, tau_h_nm);
}

const char* initialStateName(int direction) noexcept {
  switch (direction) {
    case kInitialSpeed:
      return "initial_speed_radps";
    case kInitialTorqueOffset:
      return "initial_torque_offset_nm";
    default:
      return "unknown";
  }
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
  for (std::size_t c = 0; c < log.columns.size(); ++c) {
    const auto& column = log.columns[c];
    for (std::size_t k = 0; k < column.size(); ++k) {
      if (!std::isfinite(column[k])) {
        throw std::invalid_argument("experiment log: a non-finite value at row " + std::to_string(k + 1) +
                                    (c < log.names.size() ? " of column " + log.names[c] : std::string()));
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

Simulation simulateClosedLoop(const GreyModel& model, const ExperimentData& data, const InitialState& initial) {
  // (I1)-(I2) in closed loop, in plain doubles.
  Trajectory<double> t = simulate(model, model.value, data, initial.speed_radps, initial.torque_offset_nm);
  Simulation s;
  s.q_rad = std::move(t.q_rad);
  s.tau_nm = std::move(t.tau_nm);
  s.tau_hydraulic_nm = std::move(t.tau_hydraulic_nm);
  s.command_v = std::move(t.command_v);
  s.ok = t.ok;
  return s;
}

SimulationSensitivity simulateSensitivities(const GreyModel& model, const ExperimentData& data,
                                            const InitialState& initial, const std::vector<int>& directions) {
  for (int i : directions) {
    if (i < 0 || i > kInitialTorqueOffset) {
      throw std::invalid_argument("simulation sensitivities: direction " + std::to_string(i) +
                                  " is neither a model parameter nor an initial state");
    }
  }
  const auto n = static_cast<Eigen::Index>(data.q_rad.size());
  const auto p = static_cast<Eigen::Index>(directions.size());
  SimulationSensitivity out;
  out.simulation = simulateClosedLoop(model, data, initial);
  out.q_rad.setZero(n, p);
  out.tau_nm.setZero(n, p);
  out.tau_hydraulic_nm.setZero(n, p);
  for (std::size_t first = 0; first < directions.size(); first += kDirections) {
    std::array<int, kDirections> run{};
    run.fill(-1);
    const std::size_t count = std::min<std::size_t>(kDirections, directions.size() - first);
    for (std::size_t j = 0; j < count; ++j) run[j] = directions[first + j];
    // I10: the discretised simulation differentiated forward, dx_{k+1}/dθ = Φ_x dx_k/dθ + Φ_θ,
    // through every RK4 sub-step, in dual numbers.
    const Trajectory<Sens> s = simulateDirections(model, data, initial, run);
    for (Eigen::Index k = 0; k < n; ++k) {
      // A diverged run stops early: its remaining samples stay zero, as in the simulation.
      for (std::size_t j = 0; j < count; ++j) {
        const auto col = static_cast<Eigen::Index>(first + j);
        out.q_rad(k, col) = s.q_rad[static_cast<std::size_t>(k)].d[j];
        out.tau_nm(k, col) = s.tau_nm[static_cast<std::size_t>(k)].d[j];
        out.tau_hydraulic_nm(k, col) = s.tau_hydraulic_nm[static_cast<std::size_t>(k)].d[j];
      }
    }
  }
  return out;
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
  for (int i = 0; i < substeps; ++i) x = rk4Step(m, m.value, x, u, q_ref, h);
  sampleLoadCell(m, m.value, x, dt);
  return toVector(x);
}

Eigen::Vector2d readings(const GreyModel& m, const StateVector& v) {
  const State x = fromVector(v);
  return {x.q + m.value[kAngleOffset], measuredTorque(m, m.value, x)};
}

// Finite-difference step of each state: angle, speed, hydraulic torque, spool (V), spool rate, filtered torque.
constexpr std::array<double, kStates> kStateStep{1e-7, 1e-6, 1e-5, 1e-7, 1e-4, 1e-5};

}  // namespace

Simulation predictOneStep(const GreyModel& model, const ExperimentData& data, const PredictorNoise& noise) {
  if (!(noise.angle_rad > 0.0 && noise.torque_nm > 0.0 && noise.process_torque_nm > 0.0 &&
        noise.process_speed_radps > 0.0 && noise.torque_cell_nm >= 0.0)) {
    throw std::invalid_argument(
        "one-step prediction: every noise level must be positive (the load cell's analog "
        "noise non-negative)");
  }
  const std::size_t n = data.q_rad.size();
  Simulation s;
  s.q_rad.resize(n);
  s.tau_nm.resize(n);
  s.tau_hydraulic_nm.resize(n);
  s.command_v.resize(n);
  if (n == 0) return s;
  const auto& p = model.value;
  // The simulation's initial state.
  const State x0 = initialState(
      model, p, data.q_rad[std::min(static_cast<std::size_t>(std::max(0, model.delay_samples)), n - 1)], 0.0, 0.0);
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
  const Eigen::Matrix2d r_meas = Eigen::Vector2d(noise.angle_rad * noise.angle_rad, torque_reading_var).asDiagonal();
  const std::size_t d = static_cast<std::size_t>(std::max(0, model.delay_samples));
  const Eigen::Vector2d first = readings(model, x);
  for (std::size_t j = 0; j < std::min(d, n); ++j) {
    s.q_rad[j] = first[0];
    s.tau_nm[j] = first[1];
    s.tau_hydraulic_nm[j] = x[2];
  }
  // I9: the extended Kalman filter's predict-update cycle. State m is seen by reading m + d; the
  // command of sample m acts over [m, m + 1].
  for (std::size_t m = 0; m + d < n; ++m) {
    const std::size_t j = m + d;
    const Eigen::Vector2d predicted = readings(model, x);
    s.q_rad[j] = predicted[0];
    s.tau_nm[j] = predicted[1];
    s.tau_hydraulic_nm[j] = x[2];
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
  for (const auto& [name, spec] : {std::pair{"initial_speed_radps", &options.initial_speed},
                                   std::pair{"initial_torque_offset_nm", &options.initial_torque_offset}}) {
    if (spec->free && !(std::isfinite(spec->min) && std::isfinite(spec->max) && spec->min < spec->max)) {
      throw std::invalid_argument(std::string("grey-box fit: the bounds of ") + name + " (" +
                                  std::to_string(spec->min) + ".." + std::to_string(spec->max) +
                                  ") are not finite with min < max");
    }
    if (spec->free && !(spec->min <= 0.0 && 0.0 <= spec->max)) {
      throw std::invalid_argument(std::string("grey-box fit: the bounds of ") + name + " (" +
                                  std::to_string(spec->min) + ".." + std::to_string(spec->max) +
                                  ") do not hold 0, the state at rest");
    }
  }
  for (std::size_t e = 0; e < experiments.size(); ++e) {
    const std::vector<double>& h = experiments[e].tau_hydraulic_nm;
    if (!h.empty() && h.size() != experiments[e].q_rad.size()) {
      throw std::invalid_argument("grey-box fit: experiment " + std::to_string(e + 1) + " has " +
                                  std::to_string(h.size()) + " hydraulic torques for " +
                                  std::to_string(experiments[e].q_rad.size()) + " samples");
    }
    if (!std::all_of(h.begin(), h.end(), [](double v) { return std::isfinite(v); })) {
      throw std::invalid_argument("grey-box fit: experiment " + std::to_string(e + 1) +
                                  " has a non-finite hydraulic torque");
    }
  }
  const Coordinates c(options, experiments.size());
  // Each experiment must leave more residuals after the first max_delay_samples readings than the
  // fit has coordinates.
  for (std::size_t e = 0; e < experiments.size(); ++e) {
    const auto rows = static_cast<Eigen::Index>(experiments[e].q_rad.size());
    if (rows <= std::max(0, options.max_delay_samples) + c.size()) {
      throw std::invalid_argument("grey-box fit: experiment " + std::to_string(e + 1) + " has " + std::to_string(rows) +
                                  " samples; expected more than " +
                                  std::to_string(std::max(0, options.max_delay_samples) + c.size()) +
                                  " (the readings the delays take as logged, plus one per fitted coordinate)");
    }
  }
  Problem problem(experiments, options.max_delay_samples);
  auto say = [&](const std::string& line) {
    if (options.progress) options.progress(line);
  };
  using Clock = std::chrono::steady_clock;

  // Global stage: the start and a seeded sample of the box, at every delay; free initial states
  // from the data at each point.
  const auto t0 = Clock::now();
  struct Candidate {
    double cost = kInf;
    Point point;
  };
  core::JobPool pool(std::max(1, options.threads));
  const int samples = std::max(1, options.global_samples);
  const int delays = options.max_delay_samples + 1;
  std::vector<Candidate> candidates(static_cast<std::size_t>(samples * delays));
  const Eigen::VectorXd z_start = c.toZ(pointFromData(start, experiments, options));
  constexpr int kBlock = 25;  // points per progress line
  for (int first = 0; first < samples; first += kBlock) {
    const int count = std::min(kBlock, samples - first);
    pool.run(count * delays, [&](int task) {
      const int sample = first + task / delays;
      Eigen::VectorXd z = z_start;
      if (sample > 0) {
        core::RandomStream rng(options.seed, 0x6772657962ULL, static_cast<std::uint64_t>(sample));
        for (Eigen::Index k = 0; k < c.model_count; ++k) z[k] = rng.uniform(c.lo[k], c.hi[k]);
      }
      GreyModel m = c.modelFromZ(start, z);
      m.delay_samples = task % delays;
      const Point pt = pointFromData(m, experiments, options);
      const double cost = problem.cost(pt);
      candidates[static_cast<std::size_t>(sample * delays + task % delays)] = {std::isfinite(cost) ? cost : kInf, pt};
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
    Polished p = polish(problem, c, candidates[i].point, options.max_iterations, options.jacobian, pool);
    std::ostringstream line;
    line << "polish " << i + 1 << "/" << count << ": delay " << p.point.model.delay_samples << " samples, cost "
         << candidates[i].cost << " -> " << p.cost;
    say(line.str());
    if (p.cost < best.cost) best = std::move(p);
  }
  for (int step : {-1, 1}) {
    Point pt = best.point;
    pt.model.delay_samples += step;
    if (pt.model.delay_samples < 0 || pt.model.delay_samples > options.max_delay_samples) continue;
    Polished p = polish(problem, c, pt, options.max_iterations, options.jacobian, pool);
    say("delay " + std::to_string(pt.model.delay_samples) + " samples: cost " + std::to_string(p.cost));
    if (p.cost < best.cost) best = std::move(p);
  }
  result.polish_seconds = std::chrono::duration<double>(Clock::now() - t1).count();

  result.model = best.point.model;
  result.initial_states = best.point.initial;
  result.initial_state_standard_error.assign(experiments.size(), InitialState{0.0, 0.0});
  result.cost = best.cost;
  result.evaluations = problem.evaluations.load();
  result.sensitivity_evaluations = problem.sensitivity_evaluations.load();
  result.free_params = c.index;
  // Covariance of the fit coordinates: s^2 (J^T J)^+, s^2 the residual variance.
  const Eigen::Index np = best.jacobian.cols();
  const Eigen::Index nm = c.model_count;
  result.correlation = Eigen::MatrixXd::Identity(nm, nm);
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
               << (direction.empty() && weight < 0 ? "-" : "") << std::abs(weight) << " " << c.name(j);
          direction += term.str();
        }
        result.unidentifiable.push_back(direction);
      }
    }
    const Eigen::MatrixXd cov = s2 * norms.cwiseInverse().asDiagonal() * cov_scaled * norms.cwiseInverse().asDiagonal();
    for (Eigen::Index k = 0; k < np; ++k) {
      const double sd = std::sqrt(std::max(0.0, cov(k, k)));
      const Coordinates::Slot& slot = c.slots[static_cast<std::size_t>(k)];
      if (slot.experiment >= 0) {
        initialMember(result.initial_state_standard_error[static_cast<std::size_t>(slot.experiment)], slot.param) = sd;
        continue;
      }
      const auto i = static_cast<std::size_t>(slot.param);
      result.standard_error[i] = c.log_scaled[static_cast<std::size_t>(k)] ? sd * result.model.value[i] : sd;
      for (Eigen::Index j = 0; j < nm; ++j) {
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
