// Residual tests against their statistics: a white sequence stays inside the 99 % bounds at
// about 1 % of lags, an AR(1) sequence and a residual that is a filtered excitation do not; the
// verdict passes the true model on noisy data and fails a model with a wrong flow gain; the true
// model's one-step prediction errors are white on data whose noise entered the loop (the angle's
// through the hold, the load cell's ahead of its filter), while those of a model with twice the
// inertia are not; the simulation residual of a model whose delay is one sample late, or without
// the slow spool the data have, is correlated with the past excitation; the one-step-ahead
// prediction of the true model on noise-free data is exact to rounding, and for a wrong model
// the Kalman filter's prediction fits far better than its simulation.

#include "fullarm/identification/validation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
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
  const CorrelationTest independent = excitationResidualCorrelation(u, n, -20, 20);
  ASSERT_EQ(independent.lags.size(), 41u);
  EXPECT_LE(independent.outside, 3);
  std::vector<double> e(u.size());
  for (std::size_t k = 0; k < e.size(); ++k) e[k] = n[k] + (k >= 3 ? 0.3 * u[k - 3] : 0.0);
  const CorrelationTest leaked = excitationResidualCorrelation(u, e, -20, 20);
  // The residual follows u three samples later: the peak sits at lag +3, value 0.3 / sqrt(1.09).
  EXPECT_EQ(leaked.lags[23], 3);
  EXPECT_NEAR(leaked.values[23], 0.3 / std::sqrt(1.09), 0.03);
  EXPECT_GE(leaked.outside, 1);
  // Past excitation only: lags 0 .. 20, lag 3 at index 3.
  const CorrelationTest past = excitationResidualCorrelation(u, e, 0, 20);
  ASSERT_EQ(past.lags.size(), 21u);
  EXPECT_EQ(past.lags[3], 3);
  EXPECT_DOUBLE_EQ(past.values[3], leaked.values[23]);
  EXPECT_THROW((void)excitationResidualCorrelation(u, std::vector<double>(10, 1.0), -5, 5), std::invalid_argument);
  EXPECT_THROW((void)excitationResidualCorrelation(u, e, 5, 4), std::invalid_argument);
  EXPECT_THROW((void)residualAutocorrelation(std::vector<double>(100, 2.0), 5), std::invalid_argument);
}

// Independent coloured sequences (AR(1), a = 0.9 each): the cross-correlation's variance under
// independence is P / N with P = sum_k a^(2|k|) = (1 + a^2) / (1 - a^2) = 9.53 (Ljung 16.6), so the
// white-case bound 2.576 / sqrt(N) would see about 40 % of the lags outside; the bound used puts
// about 1 % there.
TEST(ValidationTest, CrossCorrelationBoundOfTwoIndependentColouredSequencesFollowsTheirSpectra) {
  const double a = 0.9;
  const double p_theory = (1.0 + a * a) / (1.0 - a * a);
  const std::size_t n = 20000;
  const auto ar = [&](std::uint64_t stream) {
    const auto w = whiteNoise(n, stream);
    std::vector<double> x(n);
    x[0] = w[0];
    for (std::size_t k = 1; k < n; ++k) x[k] = a * x[k - 1] + w[k];
    return x;
  };
  const double white_bound = 2.5758293035489 / std::sqrt(static_cast<double>(n));
  int outside = 0, outside_white = 0, lags = 0;
  for (std::uint64_t pair = 0; pair < 8; ++pair) {
    const auto u = ar(10 + 2 * pair);
    const auto e = ar(11 + 2 * pair);
    const CorrelationTest t = excitationResidualCorrelation(u, e, 0, 25);
    EXPECT_NEAR(t.bound / white_bound, std::sqrt(p_theory), 0.15 * std::sqrt(p_theory)) << pair;
    outside += t.outside;
    for (double v : t.values) outside_white += std::abs(v) > white_bound ? 1 : 0;
    lags += static_cast<int>(t.lags.size());
  }
  std::printf("outside: %d of %d lags (white-case bound: %d)\n", outside, lags, outside_white);
  EXPECT_LE(outside, lags * 8 / 100);
  EXPECT_GE(outside_white, lags / 5);
  // One white sequence: the bound is the white case's (P = 1 up to the estimate's noise).
  const CorrelationTest white = excitationResidualCorrelation(whiteNoise(n, 30), ar(31), 0, 25);
  EXPECT_NEAR(white.bound / white_bound, 1.0, 0.1);
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

// Closed-loop data of `truth` with its noise where the plant's enters: white angle-reading noise
// that the hold law acts on (u = K (q_hold - q - n) + r, simulated as the excitation r - K n), the
// load cell's analog noise through its first-order filter (exact discretisation) and white noise
// at the load-cell reading.
ExperimentData noisyClosedLoop(const GreyModel& truth, const std::vector<double>& excitation, double angle_noise_rad,
                               double cell_noise_nm, double reading_noise_nm) {
  ExperimentData d;
  d.hold_gain_v_per_rad = 10.0;
  const auto nq = whiteNoise(excitation.size(), 11);
  const auto nc = whiteNoise(excitation.size(), 12);
  const auto nr = whiteNoise(excitation.size(), 13);
  d.excitation_v.resize(excitation.size());
  for (std::size_t k = 0; k < excitation.size(); ++k) {
    d.excitation_v[k] = excitation[k] - d.hold_gain_v_per_rad * angle_noise_rad * nq[k];
  }
  d.q_rad.assign(excitation.size(), 0.0);
  const Simulation s = simulateClosedLoop(truth, d);
  EXPECT_TRUE(s.ok);
  d.excitation_v = excitation;
  d.q_rad = s.q_rad;
  d.tau_nm = s.tau_nm;
  const double a = std::exp(-2.0 * std::numbers::pi * truth.torque_filter_hz * kT);
  double filtered = 0.0;
  for (std::size_t k = 0; k < d.q_rad.size(); ++k) {
    d.q_rad[k] += angle_noise_rad * nq[k];
    d.tau_nm[k] += filtered + reading_noise_nm * nr[k];
    filtered = a * filtered + (1.0 - a) * cell_noise_nm * nc[k];
  }
  return d;
}

GreyModel filteredTruth() {
  GreyModel truth;
  truth.value = {0.4, 8.0e3, 5.0e-4, 0.06, 0.8, 0.6, 0.0, 4.0, 0.0, 0.0, 0.0};
  truth.delay_samples = 1;
  truth.torque_filter_hz = 200.0;
  return truth;
}

ValidationThresholds sensorThresholds() {
  ValidationThresholds t;
  t.prediction.angle_rad = 2.4e-4;
  t.prediction.torque_nm = 0.0072;
  t.prediction.torque_cell_nm = 0.05;
  return t;
}

bool whitenessFails(const ChannelValidation& c, const ValidationThresholds& t) {
  return c.autocorrelation.outside > t.whiteness_max_outside_fraction * static_cast<double>(c.autocorrelation.lags.size());
}

TEST(ValidationTest, TrueModelsPredictionErrorsAreWhiteAndWrongModelsAreNot) {
  const GreyModel truth = filteredTruth();
  const ExperimentData d = noisyClosedLoop(truth, prbs(1.5, 10, 3, 1, kT).value_v, 2.4e-4, 0.05, 0.0072);
  const ValidationThresholds t = sensorThresholds();
  const ModelValidation good = validateModel(truth, d, t);
  EXPECT_TRUE(good.pass) << (good.failures.empty() ? "" : good.failures.front());
  EXPECT_FALSE(whitenessFails(good.angle, t)) << good.angle.autocorrelation.outside;
  EXPECT_FALSE(whitenessFails(good.torque, t)) << good.torque.autocorrelation.outside;
  EXPECT_EQ(good.angle.autocorrelation.label, "angle one-step prediction error (whiteness)");

  GreyModel heavy = truth;
  heavy.value[kInertia] *= 2.0;
  const ModelValidation heavy_v = validateModel(heavy, d, t);
  EXPECT_FALSE(heavy_v.pass);
  EXPECT_TRUE(whitenessFails(heavy_v.angle, t)) << heavy_v.angle.autocorrelation.outside;
  EXPECT_TRUE(whitenessFails(heavy_v.torque, t)) << heavy_v.torque.autocorrelation.outside;

  // A delay one sample late: the filter, given more process noise, absorbs most of it in its
  // prediction errors (a few lags outside, no more than the limit allows on one channel), so the
  // simulation residual's dependence on the past excitation is what shows it, at most lags.
  GreyModel late = truth;
  late.delay_samples += 1;
  const ModelValidation late_v = validateModel(late, d, t);
  EXPECT_FALSE(late_v.pass);
  EXPECT_GT(late_v.angle.cross_correlation.outside, late_v.angle.cross_correlation.lags.size() / 2);
  EXPECT_GT(late_v.torque.cross_correlation.outside, late_v.torque.cross_correlation.lags.size() / 2);
}

TEST(ValidationTest, SimulationResidualOfAModelMissingTheSpoolIsCorrelatedWithThePastExcitation) {
  GreyModel truth = filteredTruth();
  truth.spool_hz = 25.0;
  truth.spool_damping = 0.7;
  const ExperimentData d = noisyClosedLoop(truth, prbs(1.5, 10, 3, 1, kT).value_v, 2.4e-4, 0.05, 0.0072);
  const ValidationThresholds t = sensorThresholds();
  const auto fails = [&](const ChannelValidation& c) {
    return c.cross_correlation.outside >
           t.independence_max_outside_fraction * static_cast<double>(c.cross_correlation.lags.size());
  };
  const ModelValidation good = validateModel(truth, d, t);
  EXPECT_FALSE(fails(good.angle)) << good.angle.cross_correlation.outside;
  EXPECT_FALSE(fails(good.torque)) << good.torque.cross_correlation.outside;
  ASSERT_EQ(good.angle.cross_correlation.lags.front(), 0);
  ASSERT_EQ(good.angle.cross_correlation.lags.back(), t.max_lag);
  GreyModel no_spool = truth;
  no_spool.spool_hz = 0.0;
  const ModelValidation bad = validateModel(no_spool, d, t);
  EXPECT_FALSE(bad.pass);
  EXPECT_TRUE(fails(bad.angle) || fails(bad.torque))
      << bad.angle.cross_correlation.outside << " " << bad.torque.cross_correlation.outside;
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
