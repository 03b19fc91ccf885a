#pragma once
/// @file
/// Validation of an identified joint model on an experiment it was not fitted to: fit
/// percentage of angle and torque as pure simulation of the closed loop (the model sees only the
/// excitation; MATLAB's `compare` with an infinite horizon) and, reported beside it, as one-step-ahead
/// prediction (a Kalman filter on the readings up to the previous sample; horizon 1), residual autocorrelation and
/// excitation-residual cross-correlation against their 99 % bounds, and a verdict against
/// thresholds (config/identification.yaml).

#include <vector>

#include "fullarm/identification/grey_box.hpp"

namespace fullarm::identification {

/// A normalised correlation sequence and its 99 % whiteness bound +-2.576 / sqrt(N).
struct CorrelationTest {
  std::vector<int> lags;
  std::vector<double> values;
  double bound = 0.0;
  int outside = 0;  ///< lags whose |value| exceeds the bound
};

/// Autocorrelation r(tau) / r(0) of the residual at lags 1 .. max_lag (I7).
/// @throws std::invalid_argument for max_lag < 1, too short or an all-zero residual
[[nodiscard]] CorrelationTest residualAutocorrelation(const std::vector<double>& residual, int max_lag);

/// Cross-correlation of the mean-removed excitation u with the residual e at lags
/// -max_lag .. max_lag, sum_k u_k e_{k+tau} / sqrt(sum u^2 sum e^2) (I7).
/// @throws std::invalid_argument for unequal lengths, max_lag < 1 or a zero signal
[[nodiscard]] CorrelationTest excitationResidualCorrelation(const std::vector<double>& excitation,
                                                            const std::vector<double>& residual, int max_lag);

/// Thresholds of the verdict.
struct ValidationThresholds {
  double min_fit_angle_percent = 90.0;
  double min_fit_torque_percent = 70.0;
  int max_lag = 25;
  /// Largest fraction of lags outside the 99 % bounds (about 1 % for a white residual).
  double max_outside_fraction = 0.1;
  /// Noise levels of the one-step-ahead prediction's Kalman filter (reported, not judged).
  PredictorNoise prediction;
};

/// Validation of one channel.
struct ChannelValidation {
  double fit_percent = 0.0;             ///< simulation fit (the verdict's)
  double prediction_fit_percent = 0.0;  ///< one-step-ahead prediction fit (predictOneStep), reported beside it
  CorrelationTest autocorrelation;
  CorrelationTest cross_correlation;
};

/// Validation of a model on one experiment.
struct ModelValidation {
  ChannelValidation angle, torque;
  bool pass = false;
  std::vector<std::string> failures;  ///< one sentence per threshold missed
};

/// Simulates `model` on `data` and judges it against `thresholds` (the residual tests and the
/// verdict are the simulation's); also predicts it one step ahead (predictOneStep) and reports that fit.
[[nodiscard]] ModelValidation validateModel(const GreyModel& model, const ExperimentData& data,
                                            const ValidationThresholds& thresholds);

}  // namespace fullarm::identification
