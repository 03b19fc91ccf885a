#include "fullarm/design/margins.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace fullarm::design {

namespace {

constexpr int kBisectionSteps = 60;
constexpr int kGoldenSteps = 60;

// Root of f on [a, b] (f(a), f(b) of opposite signs), bisected in log frequency.
template <typename F>
double bisectLog(const F& f, double a, double b) {
  double fa = f(a);
  for (int i = 0; i < kBisectionSteps; ++i) {
    const double m = std::sqrt(a * b);
    const double fm = f(m);
    if ((fm < 0.0) == (fa < 0.0)) {
      a = m;
      fa = fm;
    } else {
      b = m;
    }
  }
  return std::sqrt(a * b);
}

// Maximum of f on [a, b] (unimodal near the grid maximum), golden section in log frequency.
template <typename F>
double goldenMaxLog(const F& f, double a, double b) {
  const double r = (std::sqrt(5.0) - 1.0) / 2.0;
  double la = std::log(a);
  double lb = std::log(b);
  double l1 = lb - r * (lb - la);
  double l2 = la + r * (lb - la);
  double f1 = f(std::exp(l1));
  double f2 = f(std::exp(l2));
  for (int i = 0; i < kGoldenSteps; ++i) {
    if (f1 < f2) {
      la = l1;
      l1 = l2;
      f1 = f2;
      l2 = la + r * (lb - la);
      f2 = f(std::exp(l2));
    } else {
      lb = l2;
      l2 = l1;
      f2 = f1;
      l1 = lb - r * (lb - la);
      f1 = f(std::exp(l1));
    }
  }
  return std::exp(0.5 * (la + lb));
}

// Phase margin of one gain crossover, wrapped to (-180, 180] degrees.
double phaseMarginDeg(std::complex<double> l) {
  double pm = std::arg(l) * 180.0 / std::numbers::pi + 180.0;
  while (pm > 180.0) pm -= 360.0;
  while (pm <= -180.0) pm += 360.0;
  return pm;
}

}  // namespace

// T3: gain, phase and delay margins, Ms (reports/equations.md).
LoopMargins computeMargins(const LoopResponse& loop, const MarginOptions& options) {
  double w_max = options.w_max_radps;
  const bool discrete = options.sample_time_s > 0.0;
  const double nyquist = discrete ? std::numbers::pi / options.sample_time_s : 0.0;
  if (discrete) w_max = std::min(w_max, nyquist);
  if (!(options.w_min_radps > 0.0) || !(w_max > options.w_min_radps)) {
    throw std::invalid_argument("computeMargins: expected 0 < w_min_radps < w_max_radps (and < pi/T if discrete)");
  }
  if (options.grid_points < 16) throw std::invalid_argument("computeMargins: expected at least 16 grid points");
  const int n = options.grid_points;
  std::vector<double> w(static_cast<std::size_t>(n));
  std::vector<std::complex<double>> l(static_cast<std::size_t>(n));
  const double la = std::log(options.w_min_radps);
  const double lb = std::log(w_max);
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    w[k] = i == n - 1 ? w_max : std::exp(la + (lb - la) * i / (n - 1));
    l[k] = loop(w[k]);
  }

  LoopMargins m;
  const auto imag = [&](double x) { return loop(x).imag(); };
  const auto gain = [&](double x) { return std::abs(loop(x)) - 1.0; };
  const auto sensitivity = [&](double x) { return 1.0 / std::abs(1.0 + loop(x)); };
  const auto addPhaseCrossover = [&](double x) {
    const std::complex<double> lx = loop(x);
    if (!(lx.real() < 0.0)) return;
    m.phase_crossovers_radps.push_back(x);
    const double gm = 1.0 / std::abs(lx);
    if (gm >= 1.0 && gm < m.gain_margin) {
      m.gain_margin = gm;
      m.gain_margin_radps = x;
    } else if (gm < 1.0 && gm > m.lower_gain_margin) {
      m.lower_gain_margin = gm;
      m.lower_gain_margin_radps = x;
    }
  };
  std::size_t ms_index = 0;
  std::size_t re_index = 0;
  for (std::size_t k = 0; k < l.size(); ++k) {
    if (std::abs(1.0 + l[k]) < std::abs(1.0 + l[ms_index])) ms_index = k;
    if (l[k].real() < l[re_index].real()) re_index = k;
    if (k == 0) continue;
    // Phase crossover: Im L changes sign where Re L < 0.
    const double i0 = l[k - 1].imag();
    const double i1 = l[k].imag();
    if ((i0 < 0.0) != (i1 < 0.0) && (l[k - 1].real() < 0.0 || l[k].real() < 0.0)) {
      addPhaseCrossover(bisectLog(imag, w[k - 1], w[k]));
    }
    // Gain crossover: |L| - 1 changes sign.
    const double g0 = std::abs(l[k - 1]) - 1.0;
    const double g1 = std::abs(l[k]) - 1.0;
    if ((g0 < 0.0) != (g1 < 0.0)) {
      const double wc = bisectLog(gain, w[k - 1], w[k]);
      m.gain_crossovers_radps.push_back(wc);
      const double pm = phaseMarginDeg(loop(wc));
      if (std::abs(pm) < std::abs(m.phase_margin_deg)) {
        m.phase_margin_deg = pm;
        m.phase_margin_radps = wc;
      }
      if (pm > 0.0) {
        const double dm = pm * std::numbers::pi / 180.0 / wc;
        if (dm < m.delay_margin_s) {
          m.delay_margin_s = dm;
          m.delay_margin_radps = wc;
        }
      } else {
        m.delay_margin_s = std::min(m.delay_margin_s, 0.0);
      }
    }
  }
  // A discrete loop is real at the Nyquist frequency: a phase crossover when it is negative.
  if (discrete && w_max >= nyquist && std::abs(l.back().imag()) <= 1e-12 * std::max(1.0, std::abs(l.back()))) {
    addPhaseCrossover(w_max);
  }
  // Peak sensitivity and minimum real part, refined around their grid extrema.
  const auto refine = [&](std::size_t k, const auto& f) {
    const double a = w[k == 0 ? 0 : k - 1];
    const double b = w[std::min(k + 1, w.size() - 1)];
    const double x = goldenMaxLog(f, a, b);
    return f(x) > f(w[k]) ? x : w[k];
  };
  const double w_ms = refine(ms_index, sensitivity);
  m.peak_sensitivity = sensitivity(w_ms);
  m.peak_sensitivity_radps = w_ms;
  const double w_re = refine(re_index, [&](double x) { return -loop(x).real(); });
  m.min_real = loop(w_re).real();
  m.min_real_radps = w_re;
  return m;
}

}  // namespace fullarm::design
