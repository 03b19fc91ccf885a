// Residual tests against their statistics: a white sequence stays inside the 99 % bounds at
// about 1 % of lags, an AR(1) sequence and a residual that is a filtered excitation do not; the
// verdict passes the true model on noisy data and fails a model with a wrong flow gain; the
// one-step-ahead prediction of the true model on noise-free data is exact to rounding, and for a
// wrong model the Kalman filter's prediction fits far better than its simulation.

#include "fullarm/identification/validation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fullarm/core/random.hpp"
#include "fullarm/identification/excitation.hpp"

namespace fullarm::identification {
namespace {

constexpr double kT = 1.0e-3;

std::vector<double> whiteNoise(std::size_t n, std::uint64_t stream) {
  std::vector<double> v(n);
  for (std::size_t k = 0; k < n; ++k) {
    core::RandomStream rng(5, stream, k);
    const double u1 = 1.0 - rng.uniform01();
    const double u2 = rng.uniform01();
    v[k] = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
  }
  return v;
}

TEST(ValidationTest, WhiteResidualStaysInsideTheBoundsAndColouredDoesNot) {
  const auto e = whiteNoise(20000, 1);
  const CorrelationTest white = residualAutocorrelation(e, 50);
  EXPECT_NEAR(white.bound, 2.5758293035489 / std::sqrt(20000.0), 1e-12);
  EXPECT_LE(white.outside, 3);  // expected 0.5 of 50 lags
  std::vector<double> ar(e.size());
  ar[0] = e[0];
  for (std::size_t k = 1; k < e.size(); ++k) ar[k] = 0.5 * ar[k - 1] + e[k];
  const CorrelationTest coloured = residualAutocorrelation(ar, 50);
  EXPECT_NEAR(coloured.values[0], 0.5, 0.03);   // r(1) = a for AR(1)
  EXPECT_NEAR(coloured.values[1], 0.25, 0.03);  // r(2) = a^2
  EXPECT_GE(coloured.outside, 3);
}

TEST(ValidationTest, CrossCorrelationFindsAFilteredExcitationInTheResidual) {
  const auto u = whiteNoise(20000, 2);
  const auto n = whiteNoise(20000, 3);
  const CorrelationTest independent = excitationResidualCorrelation(u, n, 20);
  ASSERT_EQ(independent.lags.size(), 41u);
  EXPECT_LE(independent.outside, 3);
  std::vector<double> e(u.size());
  for (std::size_t k = 0; k < e.size(); ++k) e[k] = n[k] + (k >= 3 ? 0.3 * u[k - 3] : 0.0);
  const CorrelationTest leaked = excitationResidualCorrelation(u, e, 20);
  // The residual follows u three samples later: the peak sits at lag +3, value 0.3 / sqrt(1.09).
  EXPECT_EQ(leaked.lags[23], 3);
  EXPECT_NEAR(leaked.values[23], 0.3 / std::sqrt(1.09), 0.03);
  EXPECT_GE(leaked.outside, 1);
  EXPECT_THROW((void)excitationResidualCorrelation(u, std::vector<double>(10, 1.0), 5), std::invalid_argument);
  EXPECT_THROW((void)residualAutocorrelation(std::vector<double>(100, 2.0), 5), std::invalid_argument);
}

TEST(ValidationTest, VerdictPassesTheTrueModelAndFailsAWrongOne) {
  GreyModel truth;
  truth.value = {0.4, 8.0e3, 5.0e-4, 0.06, 0.8, 0.6, 0.0, 4.0, 0.0, 0.0, 0.0};
  truth.delay_samples = 1;
  ExperimentData d;
  d.excitation_v = prbs(1.5, 11, 3, 1, kT).value_v;
  d.hold_gain_v_per_rad = 10.0;
  d.q_rad.assign(d.excitation_v.size(), 0.0);
  const Simulation s = simulateClosedLoop(truth, d);
  ASSERT_TRUE(s.ok);
  const auto nq = whiteNoise(d.excitation_v.size(), 4);
  const auto nt = whiteNoise(d.excitation_v.size(), 5);
  d.q_rad = s.q_rad;
  d.tau_nm = s.tau_nm;
  for (std::size_t k = 0; k < d.q_rad.size(); ++k) {
    d.q_rad[k] += 2e-4 * nq[k];
    d.tau_nm[k] += 0.1 * nt[k];
  }
  const ValidationThresholds thresholds;
  const ModelValidation good = validateModel(truth, d, thresholds);
  EXPECT_TRUE(good.pass) << (good.failures.empty() ? "" : good.failures.front());
  EXPECT_GT(good.angle.fit_percent, 90.0);
  GreyModel wrong = truth;
  wrong.value[kFlowGain] *= 1.5;
  const ModelValidation bad = validateModel(wrong, d, thresholds);
  EXPECT_FALSE(bad.pass);
  EXPECT_FALSE(bad.failures.empty());
}

TEST(ValidationTest, OneStepPredictionIsExactForTheTrueModelAndBeatsSimulationForAWrongOne) {
  GreyModel truth;
  truth.value = {0.4, 8.0e3, 5.0e-4, 0.06, 0.8, 0.6, 0.2, 4.0, 0.0, 0.0, 0.0};
  truth.delay_samples = 2;
  truth.spool_hz = 150.0;
  truth.torque_filter_hz = 200.0;
  truth.load_gradient_nm_per_rad = 2.0;
  ExperimentData d;
  d.excitation_v = prbs(1.5, 11, 3, 1, kT).value_v;
  d.hold_gain_v_per_rad = 10.0;
  d.q_rad.assign(d.excitation_v.size(), 0.0);
  const Simulation s = simulateClosedLoop(truth, d);
  ASSERT_TRUE(s.ok);
  d.q_rad = s.q_rad;
  d.tau_nm = s.tau_nm;
  const PredictorNoise noise;
  const Simulation p = predictOneStep(truth, d, noise);
  ASSERT_TRUE(p.ok);
  EXPECT_GT(fitPercent(d.q_rad, p.q_rad), 99.99);
  EXPECT_GT(fitPercent(d.tau_nm, p.tau_nm), 99.99);
  // The commands the predictor used are the hold law's on the readings, as the simulation's were.
  for (std::size_t k = 0; k + 2 < d.q_rad.size(); k += 97) EXPECT_NEAR(p.command_v[k], s.command_v[k], 1e-9);

  ValidationThresholds thresholds;
  GreyModel wrong = truth;
  wrong.value[kFlowGain] *= 1.5;
  wrong.value[kLoadTorque] += 1.0;
  const ModelValidation bad = validateModel(wrong, d, thresholds);
  EXPECT_LT(bad.angle.fit_percent, 70.0);
  EXPECT_GT(bad.angle.prediction_fit_percent, 80.0) << bad.angle.fit_percent;
  EXPECT_GT(bad.angle.prediction_fit_percent, bad.angle.fit_percent);
  EXPECT_GT(bad.torque.prediction_fit_percent, bad.torque.fit_percent)
      << bad.torque.fit_percent << " " << bad.torque.prediction_fit_percent;

  thresholds.prediction.torque_nm = 0.0;
  EXPECT_THROW((void)predictOneStep(truth, d, thresholds.prediction), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::identification
