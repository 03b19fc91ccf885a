#include "fullarm/design/coupled_stability.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <algorithm>
#include <array>
#include <cmath>
#include <complex>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace fullarm::design {

// C2: the detector's decay rate (reports/equations.md).
ModeDecay slowestOscillatoryMode(const Eigen::VectorXcd& poles_z, double period_s) {
  if (!(period_s > 0.0) || !std::isfinite(period_s)) {
    throw std::invalid_argument("slowestOscillatoryMode: period_s must be finite and > 0");
  }
  ModeDecay m;
  for (Eigen::Index i = 0; i < poles_z.size(); ++i) {
    const std::complex<double> z = poles_z[i];
    const double radius = std::abs(z);
    m.spectral_radius = std::max(m.spectral_radius, radius);
    const double angle = std::abs(std::arg(z));
    if (!(angle > kOscillatoryArgTolerance) || radius == 0.0) continue;  // real pole or deadbeat
    // s = ln(z) / T: Re s = ln|z| / T, Im s = arg(z) / T.
    const double sigma = -std::log(radius) / period_s;
    if (sigma < m.decay_rate_per_s) {
      const double w = angle / period_s;
      m.decay_rate_per_s = sigma;
      m.frequency_hz = w / (2.0 * std::numbers::pi);
      m.damping_ratio = sigma / std::hypot(sigma, w);
    }
  }
  return m;
}

double spectralRadiusWithoutDrift(const Eigen::VectorXcd& poles_z) {
  double rho = 0.0;
  for (Eigen::Index k = 0; k < poles_z.size(); ++k) {
    const std::complex<double> z = poles_z[k];
    if (!std::isfinite(std::abs(z))) return std::numeric_limits<double>::infinity();
    const bool drift =
        std::abs(std::arg(z)) <= kOscillatoryArgTolerance && std::abs(std::abs(z) - 1.0) <= kDriftPoleTolerance;
    if (!drift) rho = std::max(rho, std::abs(z));
  }
  return rho;
}

double detectorDecayRate(double window_s, double sustain_ratio) {
  if (!(window_s > 0.0) || !std::isfinite(window_s) || !(sustain_ratio > 0.0) || !(sustain_ratio < 1.0)) {
    throw std::invalid_argument("detectorDecayRate: expected window_s > 0 and 0 < sustain_ratio < 1");
  }
  // Eq. C2: e^{-sigma W} < r  <=>  sigma > ln(1/r) / W.
  return std::log(1.0 / sustain_ratio) / window_s;
}

// C1: coupled stability with the validated users (reports/equations.md).
std::vector<ModelVariation> coupledVariations(const ModelVariation& plant, const UncertaintyRanges& ranges) {
  std::vector<ModelVariation> out;
  const auto at = [](const UniformRange& r, double f) { return r.min + f * (r.max - r.min); };
  for (int d = ranges.delay_min_samples; d <= ranges.delay_max_samples; ++d) {
    for (double inertia : {ranges.inertia_scale.min, ranges.inertia_scale.max}) {
      for (double fb : kCoupledDampingFractions) {
        for (double fk : kCoupledStiffnessFractions) {
          ModelVariation v = plant;
          v.delay_samples = d;
          v.inertia_scale = inertia;
          v.user_damping_nms_per_rad = at(ranges.user_damping_nms_per_rad, fb);
          v.user_stiffness_nm_per_rad = at(ranges.user_stiffness_nm_per_rad, fk);
          out.push_back(v);
        }
      }
    }
  }
  return out;
}

// C1: coupled stability with the validated users (reports/equations.md).
std::vector<PreparedJoint> prepareCoupledGrid(const JointPlantModel& nominal, double q_rad, const LoopSetup& setup,
                                              const std::vector<ModelVariation>& plants,
                                              const UncertaintyRanges& ranges) {
  std::vector<PreparedJoint> out;
  for (const ModelVariation& p : plants) {
    for (const ModelVariation& v : coupledVariations(p, ranges))
      out.push_back(prepareVariation(nominal, q_rad, setup, v));
  }
  return out;
}

DetectorModel detectorModelOf(const JointScenario& sc) noexcept {
  DetectorModel d;
  d.hold_s = sc.timing.free_hold_s;
  d.window_s = sc.timing.detect_window_s;
  d.threshold_radps = sc.oscillation_speed_radps;
  d.initial_speed_radps = sc.timing.free_move_s > 0.0 ? 1.875 * sc.timing.free_move_rad / sc.timing.free_move_s : 0.0;
  d.period_s = sc.dt_s;
  d.move_amplitude_rad = sc.timing.free_move_rad;
  d.move_duration_s = sc.timing.free_move_s;
  return d;
}

// C6: contact goal (reports/equations.md).
DetectorModel contactDetectorModelOf(const JointScenario& sc) noexcept {
  DetectorModel d = detectorModelOf(sc);
  d.hold_s = sc.timing.contact_hold_s;
  const double travel = sc.timing.wall_gap_rad + sc.timing.push_rad;
  d.initial_speed_radps = sc.timing.contact_move_s > 0.0 ? 1.875 * travel / sc.timing.contact_move_s : 0.0;
  d.move_amplitude_rad = travel;
  d.move_duration_s = sc.timing.contact_move_s;
  d.modal_amplitude = false;
  return d;
}

namespace {

// Covariance (about the window mean) of a = e^{-sigma t} cos(w t), b = -e^{-sigma t} sin(w t)
// over samples [begin, end): v = V0 (a cos(phi) + b sin(phi)).
struct Cov2 {
  double aa = 0.0, ab = 0.0, bb = 0.0;
  double varAt(double c, double s) const { return c * c * aa + 2.0 * c * s * ab + s * s * bb; }
};

// e^z - 1 without cancellation for small |z|.
std::complex<double> expMinusOne(std::complex<double> z) {
  const double x = z.real(), y = z.imag();
  const double half_sin = std::sin(0.5 * y);
  return {std::expm1(x) * std::cos(y) - 2.0 * half_sin * half_sin, std::exp(x) * std::sin(y)};
}

// sum_{k = begin}^{begin + n - 1} e^{k z}, in closed form (a geometric series). e^{k z} does not
// change when Im z moves by 2 pi, so Im z is first reduced to [-pi, pi]: then e^z near 1 means z
// near 0, where expMinusOne keeps its relative accuracy. (Unreduced, a mode at a multiple of the
// sampling frequency made e^z - 1 rounding noise and the ratio meaningless.)
std::complex<double> geometricSum(std::complex<double> z, long begin, long n) {
  z = {z.real(), std::remainder(z.imag(), 2.0 * std::numbers::pi)};
  const std::complex<double> den = expMinusOne(z);
  if (den == std::complex<double>(0.0, 0.0)) return {static_cast<double>(n), 0.0};
  return std::exp(static_cast<double>(begin) * z) * expMinusOne(static_cast<double>(n) * z) / den;
}

// The sums over the window in closed form (geometric series of q^k, q = e^{(-sigma + j w) T}, and
// of q^{2k}, r^k with r = e^{-2 sigma T}): a = Re q^k, b = -Im q^k, a^2 = (r^k + Re q^{2k}) / 2,
// b^2 = (r^k - Re q^{2k}) / 2, a b = -Im q^{2k} / 2. Replaces 2 x 500 exp/sincos per window.
Cov2 windowCovariance(double sigma, double w, double T, long begin, long end) {
  const long count = end - begin;
  const std::complex<double> z(-sigma * T, w * T);
  const std::complex<double> s1 = geometricSum(z, begin, count);
  const std::complex<double> s2 = geometricSum(2.0 * z, begin, count);
  const double r = geometricSum({-2.0 * sigma * T, 0.0}, begin, count).real();
  const double sa = s1.real(), sb = -s1.imag();
  const double saa = 0.5 * (r + s2.real()), sbb = 0.5 * (r - s2.real()), sab = -0.5 * s2.imag();
  const double n = static_cast<double>(count);
  Cov2 c;
  c.aa = std::max(saa / n - (sa / n) * (sa / n), 0.0);
  c.ab = sab / n - (sa / n) * (sb / n);
  c.bb = std::max(sbb / n - (sb / n) * (sb / n), 0.0);
  return c;
}

// Power-of-two diagonal balancing (Parlett & Reinsch 1969, as LAPACK gebal without permutation):
// d such that diag(d)^-1 A diag(d) has comparable row and column norms; A is balanced in place.
// T2: diagonal balancing (reports/equations.md).
Eigen::VectorXd balance(Eigen::MatrixXd& a) {
  const Eigen::Index n = a.rows();
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  bool done = false;
  for (int sweep = 0; sweep < 100 && !done; ++sweep) {
    done = true;
    for (Eigen::Index i = 0; i < n; ++i) {
      double c = 0.0, r = 0.0;
      for (Eigen::Index j = 0; j < n; ++j) {
        if (j == i) continue;
        c += std::abs(a(j, i));
        r += std::abs(a(i, j));
      }
      // A zero or non-finite norm: nothing to balance (scaling an infinity never ends).
      if (c == 0.0 || r == 0.0 || !std::isfinite(c) || !std::isfinite(r)) continue;
      const double total = c + r;
      double f = 1.0;
      while (c < 0.5 * r) {
        c *= 4.0;
        f *= 2.0;
      }
      while (c > 2.0 * r) {
        c *= 0.25;
        f *= 0.5;
      }
      if ((c + r) / f < 0.95 * total) {
        done = false;
        d[i] *= f;
        a.row(i) /= f;
        a.col(i) *= f;
      }
    }
  }
  return d;
}

constexpr int kPhases = 360;
// Detector score of a growing mode (plus its growth rate [1/s], capped at 1e3).
constexpr double kUnstableModeScore = 10.0;

}  // namespace

// C3: detector score of a mode (reports/equations.md).
double detectorModeScore(double sigma, double w, const DetectorModel& d) {
  if (!(d.window_s > 0.0) || !(d.hold_s >= 2.0 * d.window_s) || !(d.threshold_radps > 0.0) ||
      !(d.sustain_ratio > 0.0) || !(d.initial_speed_radps >= 0.0) || !(d.period_s > 0.0)) {
    throw std::invalid_argument("detectorModeScore: expected hold_s >= 2 window_s > 0, threshold, ratio, period > 0");
  }
  // The hold runs on the control samples 0 .. N-1 (t from the start of the hold), as examineHold().
  const long n = std::lround(d.hold_s / d.period_s);
  const long win = std::lround(d.window_s / d.period_s);
  const Cov2 late = windowCovariance(sigma, w, d.period_s, n - win, n);
  const Cov2 early = windowCovariance(sigma, w, d.period_s, n - 2 * win, n - win);
  double worst = 0.0;
  const int phases = w == 0.0 ? 1 : kPhases;
  // cos and sin of the phases pi i / kPhases, computed once.
  static const std::array<std::array<double, 2>, kPhases> kPhaseTable = [] {
    std::array<std::array<double, 2>, kPhases> t{};
    for (int i = 0; i < kPhases; ++i) {
      const double phi = std::numbers::pi * static_cast<double>(i) / static_cast<double>(kPhases);
      t[static_cast<std::size_t>(i)] = {std::cos(phi), std::sin(phi)};
    }
    return t;
  }();
  for (int i = 0; i < phases; ++i) {
    const double c = kPhaseTable[static_cast<std::size_t>(i)][0], s = kPhaseTable[static_cast<std::size_t>(i)][1];
    const double l = d.initial_speed_radps * std::sqrt(late.varAt(c, s));
    const double e = d.initial_speed_radps * std::sqrt(early.varAt(c, s));
    if (!(l > 0.0)) continue;
    const double amplitude = l / d.threshold_radps;
    const double sustained = e > 0.0 ? l / (d.sustain_ratio * e) : std::numeric_limits<double>::infinity();
    worst = std::max(worst, std::min(amplitude, sustained));
  }
  return worst;
}

// C5: modal amplitude of the free move (reports/equations.md).
std::vector<ModalSpeed> modalHoldSpeeds(const PreparedJoint& m, const controllers::JointGains& gains,
                                        const DetectorModel& d) {
  const StateSpace cl = closedLoopSystem(m, gains, VirtualWall{});
  const double T = m.setup.control_period_s;
  std::vector<ModalSpeed> out;
  const auto unscorable = [&] {  // non-finite loop or no eigen-decomposition: NaN amplitudes
    const Eigen::VectorXcd z = closedLoopPoles(m, gains, VirtualWall{});
    out.clear();
    for (Eigen::Index i = 0; i < z.size(); ++i) out.push_back({z[i], std::numeric_limits<double>::quiet_NaN()});
    return out;
  };
  if (!cl.A.allFinite() || !cl.B.allFinite()) return unscorable();
  Eigen::MatrixXd a = cl.A;
  const Eigen::VectorXd scale = balance(a);  // a = D^-1 A D
  const Eigen::EigenSolver<Eigen::MatrixXd> es(a, true);
  if (es.info() != Eigen::Success) return unscorable();
  const Eigen::VectorXcd poles = es.eigenvalues();
  const Eigen::MatrixXcd vb = es.eigenvectors();  // A = D vb diag(poles) vb^-1 D^-1
  const Eigen::VectorXd b = cl.B.col(0).cwiseQuotient(scale);
  const Eigen::VectorXcd g = vb.partialPivLu().solve(b.cast<std::complex<double>>());  // modal input
  const Eigen::RowVectorXcd c = scale[kVelocity] * vb.row(kVelocity);                  // modal speed output
  // The user's torque of the free move (validate's harness: K_h (r - q) + B_h (r' - q') with the
  // spring and damper in the plant): input K_h r(kT) + B_h r'(kT), held over period k.
  const double k_h = m.model.include_user ? m.model.load.user_stiffness_nm_per_rad : 0.0;
  const double b_h = m.model.include_user ? m.model.load.user_damping_nms_per_rad : 0.0;
  const long steps = std::lround(d.move_duration_s / T);
  std::vector<double> u(static_cast<std::size_t>(std::max(steps, 0L)));
  for (long k = 0; k < steps; ++k) {
    const MinJerk r = minimumJerk(static_cast<double>(k) * T, d.move_duration_s);
    u[static_cast<std::size_t>(k)] = d.move_amplitude_rad * (k_h * r.position + b_h * r.rate_per_s);
  }
  const double u_end = d.move_amplitude_rad * k_h;
  // Modal coordinate at the end of the move: sum_k z^(N-1-k) g u[k] (Horner), less its steady
  // state g u_end / (1 - z) under the final torque (none for a pole at 1: then u_end = 0). Every
  // pole's recurrence advances together, one input sample at a time: the same operations per
  // pole as one pole after the other, but independent ones side by side instead of a chain.
  const auto n_poles = static_cast<std::size_t>(poles.size());
  std::vector<std::complex<double>> modes(n_poles, std::complex<double>(0.0, 0.0));
  for (double uk : u) {
    for (std::size_t i = 0; i < n_poles; ++i) modes[i] = poles[static_cast<Eigen::Index>(i)] * modes[i] + uk;
  }
  out.reserve(n_poles);
  for (Eigen::Index i = 0; i < poles.size(); ++i) {
    const std::complex<double> z = poles[i];
    std::complex<double> mode = modes[static_cast<std::size_t>(i)];
    mode *= g[i];
    if (std::abs(1.0 - z) > 1e-12) mode -= g[i] * u_end / (1.0 - z);
    out.push_back({z, c[i] * mode});
  }
  return out;
}

namespace {

// Largest |z|; infinite when a pole is not finite (so that it cannot vanish in std::max).
double largestModulus(const Eigen::VectorXcd& z) {
  double largest = 0.0;
  for (Eigen::Index k = 0; k < z.size(); ++k) {
    const double r = std::abs(z[k]);
    if (!std::isfinite(r)) return std::numeric_limits<double>::infinity();
    largest = std::max(largest, r);
  }
  return largest;
}

// Scores the poles `z` of model `index` by the detector (each pole's own V0 from `amplitude`
// when given, else detector.initial_speed_radps) into `g`: its spectral radius, slowest mode
// and worst detector score. `drift_excluded`: a real pole within kDriftPoleTolerance of 1 is
// the free position's drift (left out of the radius, scored like any real mode).
void scorePoles(const Eigen::VectorXcd& z, const std::vector<double>* amplitude, double T,
                const DetectorModel& detector, bool drift_excluded, int index, CoupledGoal& g) {
  // Poles faster than this leave less than 1e-3 of the threshold in the late window.
  const auto skipAbove = [&](double v0) {
    return std::log(1e3 * std::max(v0, detector.threshold_radps) / detector.threshold_radps) /
           (detector.hold_s - detector.window_s);
  };
  const ModeDecay d = slowestOscillatoryMode(z, T);
  // Spectral radius without the free-position drift (a real pole within kDriftPoleTolerance of
  // z = 1: with K_h = 0 the position has no restoring torque, and the residual slope of the
  // gravity compensation leaves it at |z| = 1 + 1e-7 or so, an e-folding time of hours).
  g.spectral_radius = std::max(g.spectral_radius, drift_excluded ? spectralRadiusWithoutDrift(z) : largestModulus(z));
  if (g.worst_model < 0 || d.decay_rate_per_s < g.slowest.decay_rate_per_s) {
    g.slowest = d;
    g.worst_model = index;
  }
  for (Eigen::Index k = 0; k < z.size(); ++k) {
    const double radius = std::abs(z[k]);
    if (radius == 0.0 || z[k].imag() < 0.0) continue;  // deadbeat, or the conjugate of a pole seen
    const double sigma = -std::log(radius) / T;
    DetectorModel mode_detector = detector;
    if (amplitude != nullptr) {
      // A non-finite modal amplitude (non-finite loop) falls back to Eq. C3's bound, so that the
      // pole, not the amplitude, decides whether the goal is scorable.
      const double v0 = (*amplitude)[static_cast<std::size_t>(k)];
      mode_detector.initial_speed_radps = std::isfinite(v0) ? v0 : detector.initial_speed_radps;
    }
    if (sigma > skipAbove(mode_detector.initial_speed_radps)) continue;
    const double angle = std::abs(std::arg(z[k]));
    const double w = angle > kOscillatoryArgTolerance ? angle / T : 0.0;
    if (drift_excluded && w == 0.0 && std::abs(radius - 1.0) <= kMarginalPoleTolerance) continue;  // free position
    // A growing mode fails outright; the score stays finite (and rises with the growth rate) so
    // that the optimisers see a slope instead of an infinity.
    const bool drift = drift_excluded && w == 0.0 && radius <= 1.0 + kDriftPoleTolerance;  // scored like any real mode
    const double score =
        sigma < 0.0 && !drift ? kUnstableModeScore + std::min(-sigma, 1e3) : detectorModeScore(sigma, w, mode_detector);
    if (score > g.detector_score) {
      g.detector_score = score;
      g.detector_hz = w / (2.0 * std::numbers::pi);
      g.detector_decay_per_s = sigma;
      g.detector_model = index;
    }
  }
}

}  // namespace

// C1: coupled stability with the validated users; C5: modal amplitude of the free move (reports/equations.md).
CoupledGoal evaluateCoupled(const std::vector<PreparedJoint>& models, const controllers::JointGains& gains,
                            const DetectorModel& detector) {
  CoupledGoal g;
  for (std::size_t i = 0; i < models.size(); ++i) {
    const PreparedJoint& m = models[i];
    const double T = m.setup.control_period_s;
    if (detector.modal_amplitude) {
      const std::vector<ModalSpeed> modes = modalHoldSpeeds(m, gains, detector);
      Eigen::VectorXcd z(static_cast<Eigen::Index>(modes.size()));
      std::vector<double> amplitude;  // each pole's V0
      for (std::size_t k = 0; k < modes.size(); ++k) {
        z[static_cast<Eigen::Index>(k)] = modes[k].pole;
        // A conjugate pair's speed is 2 Re(c z^n): amplitude 2 |c|; a real pole's (z > 0 or z < 0) |c|.
        const std::complex<double> zk = modes[k].pole;
        const bool pair = std::abs(zk.imag()) > kOscillatoryArgTolerance * std::abs(zk);
        amplitude.push_back((pair ? 2.0 : 1.0) * std::abs(modes[k].coefficient));
      }
      scorePoles(z, &amplitude, T, detector, true, static_cast<int>(i), g);
    } else {
      scorePoles(closedLoopPoles(m, gains, VirtualWall{}), nullptr, T, detector, true, static_cast<int>(i), g);
    }
  }
  g.slowest.spectral_radius = g.spectral_radius;
  return g;
}

// C6: contact goal (reports/equations.md).
CoupledGoal evaluateCoupledContact(const std::vector<PreparedJoint>& models, const controllers::JointGains& gains,
                                   const VirtualWall& wall, const DetectorModel& contact_detector) {
  CoupledGoal g;
  for (std::size_t i = 0; i < models.size(); ++i) {
    const PreparedJoint& m = models[i];
    scorePoles(closedLoopPoles(m, gains, wall), nullptr, m.setup.control_period_s, contact_detector, false,
               static_cast<int>(i), g);
  }
  g.slowest.spectral_radius = g.spectral_radius;
  return g;
}

// C3: detector score of a mode (reports/equations.md).
double coupledGoalValue(const CoupledGoal& goal) noexcept {
  return std::max(goal.spectral_radius - kMarginalPoleTolerance, goal.detector_score);
}

}  // namespace fullarm::design
