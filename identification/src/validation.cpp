#include "fullarm/identification/validation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fullarm::identification {
namespace {

// 99 % two-sided quantile of the standard normal distribution.
constexpr double kNormal99 = 2.5758293035489;

// Lags over which the cross-correlation's variance under independence is summed (a quarter of a
// second at 1 kHz), and its floor: the estimate, a sum of sample correlations, is noisy, and never
// taken below a quarter of the white case's.
constexpr std::size_t kCrossBoundLags = 250;
constexpr double kMinCrossVariance = 0.25;

double mean(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m += x;
  return m / static_cast<double>(v.size());
}

}  // namespace

CorrelationTest residualAutocorrelation(const std::vector<double>& residual, int max_lag) {
  if (max_lag < 1) throw std::invalid_argument("autocorrelation: max_lag must be >= 1");
  const std::size_t n = residual.size();
  if (n <= static_cast<std::size_t>(max_lag)) {
    throw std::invalid_argument("autocorrelation: " + std::to_string(n) + " samples for " + std::to_string(max_lag) +
                                " lags");
  }
  const double m = mean(residual);
  double r0 = 0.0;
  for (double e : residual) r0 += (e - m) * (e - m);
  if (!(r0 > 0.0)) throw std::invalid_argument("autocorrelation: the residual is constant");
  CorrelationTest t;
  t.bound = kNormal99 / std::sqrt(static_cast<double>(n));
  // I7: normalised sample correlation and its whiteness bound.
  for (int lag = 1; lag <= max_lag; ++lag) {
    double r = 0.0;
    for (std::size_t k = 0; k + static_cast<std::size_t>(lag) < n; ++k) {
      r += (residual[k] - m) * (residual[k + static_cast<std::size_t>(lag)] - m);
    }
    t.lags.push_back(lag);
    t.values.push_back(r / r0);
    if (std::abs(r / r0) > t.bound) ++t.outside;
  }
  return t;
}

CorrelationTest excitationResidualCorrelation(const std::vector<double>& excitation,
                                              const std::vector<double>& residual, int min_lag, int max_lag) {
  if (excitation.size() != residual.size()) {
    throw std::invalid_argument("cross-correlation: excitation and residual differ in length");
  }
  if (min_lag > max_lag) throw std::invalid_argument("cross-correlation: min_lag above max_lag");
  const std::size_t n = residual.size();
  if (n <= static_cast<std::size_t>(std::max(std::abs(min_lag), std::abs(max_lag)))) {
    throw std::invalid_argument("cross-correlation: too few samples");
  }
  const double mu = mean(excitation);
  const double me = mean(residual);
  double suu = 0.0, see = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    suu += (excitation[k] - mu) * (excitation[k] - mu);
    see += (residual[k] - me) * (residual[k] - me);
  }
  if (!(suu > 0.0) || !(see > 0.0)) throw std::invalid_argument("cross-correlation: a constant signal");
  const double norm = std::sqrt(suu * see);
  // I7: under independence sqrt(N) r_ue(tau) tends to a normal law of variance
  // P = sum_k rho_u(k) rho_e(k) (Ljung 16.6, P_1), which is 1 only when one of the two is white: a
  // band-limited excitation and a loop-coloured residual make it several times that. The sum is
  // taken over |k| <= kCrossBoundLags (or a quarter of the record), where a residual's correlation
  // has died out.
  const auto autocorrelationAt = [&](const std::vector<double>& x, double m, double s0, std::size_t lag) {
    double r = 0.0;
    for (std::size_t k = 0; k + lag < n; ++k) r += (x[k] - m) * (x[k + lag] - m);
    return r / s0;
  };
  const std::size_t span = std::min<std::size_t>(kCrossBoundLags, (n - 1) / 4);
  double variance = 1.0;
  for (std::size_t lag = 1; lag <= span; ++lag) {
    variance += 2.0 * autocorrelationAt(excitation, mu, suu, lag) * autocorrelationAt(residual, me, see, lag);
  }
  CorrelationTest t;
  t.bound = kNormal99 * std::sqrt(std::max(variance, kMinCrossVariance) / static_cast<double>(n));
  // Normalised cross-correlation against that bound.
  for (int lag = min_lag; lag <= max_lag; ++lag) {
    double r = 0.0;
    for (std::size_t k = 0; k < n; ++k) {
      const long j = static_cast<long>(k) + lag;
      if (j < 0 || j >= static_cast<long>(n)) continue;
      r += (excitation[k] - mu) * (residual[static_cast<std::size_t>(j)] - me);
    }
    t.lags.push_back(lag);
    t.values.push_back(r / norm);
    if (std::abs(r / norm) > t.bound) ++t.outside;
  }
  return t;
}

namespace {

// The prediction-error criterion with unknown noise covariance: the determinant of the
// innovations' sample covariance over the readings after the delay (before it the filter has seen nothing).
double innovationDeterminant(const ExperimentData& data, const Simulation& p, std::size_t first) {
  if (!p.ok || data.q_rad.size() <= first + 2) return std::numeric_limits<double>::infinity();
  double sqq = 0.0, stt = 0.0, sqt = 0.0, mq = 0.0, mt = 0.0;
  const auto count = static_cast<double>(data.q_rad.size() - first);
  for (std::size_t j = first; j < data.q_rad.size(); ++j) {
    mq += data.q_rad[j] - p.q_rad[j];
    mt += data.tau_nm[j] - p.tau_nm[j];
  }
  mq /= count;
  mt /= count;
  for (std::size_t j = first; j < data.q_rad.size(); ++j) {
    const double eq = data.q_rad[j] - p.q_rad[j] - mq;
    const double et = data.tau_nm[j] - p.tau_nm[j] - mt;
    sqq += eq * eq;
    stt += et * et;
    sqt += eq * et;
  }
  const double det = (sqq * stt - sqt * sqt) / (count * count);
  return std::isfinite(det) ? det : std::numeric_limits<double>::infinity();
}

}  // namespace

TunedPredictor tunePredictorNoise(const GreyModel& model, const ExperimentData& data, const PredictorNoise& noise) {
  TunedPredictor best;
  best.noise = noise;
  best.prediction.ok = false;
  double best_cost = std::numeric_limits<double>::infinity();
  int best_k = 0;
  const std::size_t first = static_cast<std::size_t>(std::max(0, model.delay_samples));
  const auto trial = [&](int k) {
    const double scale = std::pow(10.0, 0.5 * k);
    PredictorNoise n = noise;
    n.process_torque_nm *= scale;
    n.process_speed_radps *= scale;
    Simulation p = predictOneStep(model, data, n);
    const double cost = innovationDeterminant(data, p, first);
    if (cost < best_cost) {
      best_cost = cost;
      best_k = k;
      best.noise = n;
      best.process_scale = scale;
      best.prediction = std::move(p);
    }
  };
  // I11: the process-noise scale minimising det of the innovations' covariance; whole decades
  // 1e-4 .. 1e2, then the half decades either side of the best.
  for (int k = -8; k <= 4; k += 2) trial(k);
  if (std::isfinite(best_cost)) {
    const int centre = best_k;
    if (centre > -8) trial(centre - 1);
    if (centre < 4) trial(centre + 1);
  }
  return best;
}

ModelValidation validateModel(const GreyModel& model, const ExperimentData& data,
                              const ValidationThresholds& thresholds) {
  ModelValidation v;
  const Simulation s = simulateClosedLoop(model, data);
  if (!s.ok) {
    v.failures.emplace_back("the model's closed loop diverges on this experiment");
    return v;
  }
  const TunedPredictor predictor = tunePredictorNoise(model, data, thresholds.prediction);
  v.process_scale = predictor.process_scale;
  const std::size_t first = static_cast<std::size_t>(std::max(0, model.delay_samples));
  auto channel = [&](const char* name, const std::vector<double>& measured, const std::vector<double>& simulated,
                     const std::vector<double>& predicted) {
    ChannelValidation c;
    c.fit_percent = fitPercent(measured, simulated);
    std::vector<double> e(measured.size());
    for (std::size_t k = 0; k < e.size(); ++k) e[k] = measured[k] - simulated[k];
    c.cross_correlation = excitationResidualCorrelation(data.excitation_v, e, 0, thresholds.max_lag);
    c.cross_correlation.label = std::string(name) + " simulation residual vs past excitation (independence)";
    if (predictor.prediction.ok) {
      c.prediction_fit_percent = fitPercent(measured, predicted);
      // The first d predictions are the initial state's (no reading has reached the filter yet).
      std::vector<double> innovation;
      for (std::size_t k = first; k < measured.size(); ++k) innovation.push_back(measured[k] - predicted[k]);
      c.autocorrelation = residualAutocorrelation(innovation, thresholds.max_lag);
    } else {
      c.prediction_fit_percent = std::numeric_limits<double>::quiet_NaN();
    }
    c.autocorrelation.label = std::string(name) + " one-step prediction error (whiteness)";
    return c;
  };
  v.angle = channel("angle", data.q_rad, s.q_rad, predictor.prediction.q_rad);
  v.torque = channel("torque", data.tau_nm, s.tau_nm, predictor.prediction.tau_nm);
  if (!data.tau_hydraulic_nm.empty()) {
    if (data.tau_hydraulic_nm.size() != data.q_rad.size()) {
      throw std::invalid_argument("validation: " + std::to_string(data.tau_hydraulic_nm.size()) +
                                  " hydraulic torques for " + std::to_string(data.q_rad.size()) + " samples");
    }
    v.has_hydraulic = true;
    // Reported, not judged: a hydraulic torque that never changes has no fit percentage (NaN).
    const bool varies = std::any_of(data.tau_hydraulic_nm.begin(), data.tau_hydraulic_nm.end(),
                                    [&](double x) { return x != data.tau_hydraulic_nm.front(); });
    if (varies) {
      v.hydraulic_fit_percent = fitPercent(data.tau_hydraulic_nm, s.tau_hydraulic_nm);
      if (predictor.prediction.ok) {
        v.hydraulic_prediction_fit_percent = fitPercent(data.tau_hydraulic_nm, predictor.prediction.tau_hydraulic_nm);
      }
    }
  }
  if (!predictor.prediction.ok) v.failures.emplace_back("the one-step predictor diverges on this experiment");
  auto check = [&](const char* name, const ChannelValidation& c, double min_fit) {
    std::ostringstream msg;
    if (c.fit_percent < min_fit) {
      msg << name << " simulation fit " << c.fit_percent << " % below " << min_fit << " %";
      v.failures.push_back(msg.str());
      msg.str("");
    }
    const auto limit = [](const CorrelationTest& t, double fraction) {
      return fraction * static_cast<double>(t.lags.size());
    };
    if (predictor.prediction.ok &&
        c.autocorrelation.outside > limit(c.autocorrelation, thresholds.whiteness_max_outside_fraction)) {
      msg << name << " one-step prediction errors not white: " << c.autocorrelation.outside << " of "
          << c.autocorrelation.lags.size() << " lags outside the 99 % bound";
      v.failures.push_back(msg.str());
      msg.str("");
    }
    if (c.cross_correlation.outside > limit(c.cross_correlation, thresholds.independence_max_outside_fraction)) {
      msg << name << " simulation residual correlated with the past excitation: " << c.cross_correlation.outside
          << " of " << c.cross_correlation.lags.size() << " lags outside the 99 % bound";
      v.failures.push_back(msg.str());
    }
  };
  check("angle", v.angle, thresholds.min_fit_angle_percent);
  check("torque", v.torque, thresholds.min_fit_torque_percent);
  v.pass = v.failures.empty();
  return v;
}

}  // namespace fullarm::identification
