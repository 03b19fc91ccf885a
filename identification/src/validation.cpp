#include "fullarm/identification/validation.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fullarm::identification {
namespace {

// 99 % two-sided quantile of the standard normal distribution.
constexpr double kNormal99 = 2.5758293035489;

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
                                              const std::vector<double>& residual, int max_lag) {
  if (excitation.size() != residual.size()) {
    throw std::invalid_argument("cross-correlation: excitation and residual differ in length");
  }
  if (max_lag < 1) throw std::invalid_argument("cross-correlation: max_lag must be >= 1");
  const std::size_t n = residual.size();
  if (n <= static_cast<std::size_t>(max_lag)) throw std::invalid_argument("cross-correlation: too few samples");
  const double mu = mean(excitation);
  const double me = mean(residual);
  double suu = 0.0, see = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    suu += (excitation[k] - mu) * (excitation[k] - mu);
    see += (residual[k] - me) * (residual[k] - me);
  }
  if (!(suu > 0.0) || !(see > 0.0)) throw std::invalid_argument("cross-correlation: a constant signal");
  const double norm = std::sqrt(suu * see);
  CorrelationTest t;
  t.bound = kNormal99 / std::sqrt(static_cast<double>(n));
  // I7: normalised cross-correlation and the same bound.
  for (int lag = -max_lag; lag <= max_lag; ++lag) {
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

ModelValidation validateModel(const GreyModel& model, const ExperimentData& data,
                              const ValidationThresholds& thresholds) {
  ModelValidation v;
  const Simulation s = simulateClosedLoop(model, data);
  if (!s.ok) {
    v.failures.emplace_back("the model's closed loop diverges on this experiment");
    return v;
  }
  auto channel = [&](const std::vector<double>& measured, const std::vector<double>& modelled) {
    ChannelValidation c;
    c.fit_percent = fitPercent(measured, modelled);
    std::vector<double> e(measured.size());
    for (std::size_t k = 0; k < e.size(); ++k) e[k] = measured[k] - modelled[k];
    c.autocorrelation = residualAutocorrelation(e, thresholds.max_lag);
    c.cross_correlation = excitationResidualCorrelation(data.excitation_v, e, thresholds.max_lag);
    return c;
  };
  v.angle = channel(data.q_rad, s.q_rad);
  v.torque = channel(data.tau_nm, s.tau_nm);
  const Simulation predicted = predictOneStep(model, data, thresholds.prediction);
  if (predicted.ok) {
    v.angle.prediction_fit_percent = fitPercent(data.q_rad, predicted.q_rad);
    v.torque.prediction_fit_percent = fitPercent(data.tau_nm, predicted.tau_nm);
  } else {
    v.angle.prediction_fit_percent = v.torque.prediction_fit_percent = std::numeric_limits<double>::quiet_NaN();
  }
  auto check = [&](const char* name, const ChannelValidation& c, double min_fit) {
    std::ostringstream msg;
    if (c.fit_percent < min_fit) {
      msg << name << " fit " << c.fit_percent << " % below " << min_fit << " %";
      v.failures.push_back(msg.str());
      msg.str("");
    }
    const auto limit = [&](const CorrelationTest& t) {
      return thresholds.max_outside_fraction * static_cast<double>(t.lags.size());
    };
    if (c.autocorrelation.outside > limit(c.autocorrelation)) {
      msg << name << " residual not white: " << c.autocorrelation.outside << " of " << c.autocorrelation.lags.size()
          << " lags outside the 99 % bound";
      v.failures.push_back(msg.str());
      msg.str("");
    }
    if (c.cross_correlation.outside > limit(c.cross_correlation)) {
      msg << name << " residual correlated with the excitation: " << c.cross_correlation.outside << " of "
          << c.cross_correlation.lags.size() << " lags outside the 99 % bound";
      v.failures.push_back(msg.str());
    }
  };
  check("angle", v.angle, thresholds.min_fit_angle_percent);
  check("torque", v.torque, thresholds.min_fit_torque_percent);
  v.pass = v.failures.empty();
  return v;
}

}  // namespace fullarm::identification
