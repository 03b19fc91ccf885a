#pragma once
/// @file
/// Validation of an identified joint model on an experiment it was not fitted to, in the
/// prediction-error framework: fit percentage of angle and torque as pure simulation of the closed
/// loop (the model sees only the excitation; MATLAB's `compare` with an infinite horizon) and as
/// one-step-ahead prediction (a Kalman filter on the readings up to the previous sample; horizon 1),
/// and the two residual tests that apply to each: the simulation (output-error) residual, which has
/// no noise model and need not be white, must be independent of the past excitation
/// (cross-correlation at lags 0 .. max_lag); the one-step prediction errors (the filter's
/// innovations, with its process noise estimated by minimising them) must be white
/// (autocorrelation at lags 1 .. max_lag). Both against their 99 % bounds, and a verdict against
/// thresholds (config/identification.yaml).

#include <limits>
#include <string>
#include <vector>

#include "fullarm/identification/grey_box.hpp"

namespace fullarm::identification {

/// A normalised correlation sequence and its 99 % whiteness bound +-2.576 / sqrt(N).
struct CorrelationTest {
  std::string label;  ///< which residual and which test, for reports
  std::vector<int> lags;
  std::vector<double> values;
  double bound = 0.0;
  int outside = 0;  ///< lags whose |value| exceeds the bound
};

/// Autocorrelation r(tau) / r(0) of the residual at lags 1 .. max_lag (I7).
/// @throws std::invalid_argument for max_lag < 1, too short or an all-zero residual
[[nodiscard]] CorrelationTest residualAutocorrelation(const std::vector<double>& residual, int max_lag);

/// Cross-correlation of the mean-removed excitation u with the residual e at lags
/// min_lag .. max_lag, sum_k u_k e_{k+tau} / sqrt(sum u^2 sum e^2) (I7): a positive lag tau pairs the
/// residual with the excitation tau samples before it. The 99 % bound is that of independent u and
/// e, 2.576 sqrt(P / N) with P = sum_k rho_u(k) rho_e(k) over |k| <= 250 (or a quarter of the
/// record), their sample autocorrelations: 2.576 / sqrt(N) when either is white, wider for a
/// band-limited excitation and a coloured residual (P floored at 0.25).
/// @throws std::invalid_argument for unequal lengths, min_lag > max_lag, a lag range reaching the
///   record's length or a zero signal
[[nodiscard]] CorrelationTest excitationResidualCorrelation(const std::vector<double>& excitation,
                                                            const std::vector<double>& residual, int min_lag,
                                                            int max_lag);

/// The one-step-ahead predictor with its process noise estimated from the data (tunePredictorNoise).
struct TunedPredictor {
  PredictorNoise noise;        ///< the noise levels chosen
  double process_scale = 1.0;  ///< their process noise over the reference levels
  Simulation prediction;       ///< predictOneStep with `noise`; ok false when every scale diverged
};

/// The measurement noise is `noise`'s (the sensors'); the process noise levels are `noise`'s
/// scaled by the factor that minimises the determinant of the innovations' sample covariance
/// (I11, the prediction-error criterion for unknown noise covariance), searched over the decades
/// 1e-4 .. 1e2 and then the half decades either side of the best.
/// @throws std::invalid_argument for a noise level predictOneStep refuses
[[nodiscard]] TunedPredictor tunePredictorNoise(const GreyModel& model, const ExperimentData& data,
                                                const PredictorNoise& noise);

/// Thresholds of the verdict.
struct ValidationThresholds {
  double min_fit_angle_percent = 90.0;
  double min_fit_torque_percent = 70.0;
  int max_lag = 25;
  /// Whiteness of the one-step prediction errors: largest fraction of the autocorrelation's lags
  /// outside the 99 % bound (about 1 % for a white sequence).
  double whiteness_max_outside_fraction = 0.1;
  /// Independence of the simulation residual and the past excitation: largest fraction of the
  /// cross-correlation's lags 0 .. max_lag outside the 99 % bound.
  double independence_max_outside_fraction = 0.1;
  /// Measurement noise of the one-step predictor's Kalman filter and the reference levels of its
  /// process noise (scaled by tunePredictorNoise).
  PredictorNoise prediction;
};

/// Validation of one channel.
struct ChannelValidation {
  double fit_percent = 0.0;             ///< simulation fit (judged)
  double prediction_fit_percent = 0.0;  ///< one-step-ahead prediction fit (predictOneStep), reported beside it
  CorrelationTest autocorrelation;      ///< of the one-step prediction errors (whiteness, judged)
  CorrelationTest cross_correlation;    ///< of the simulation residual with the past excitation (independence, judged)
};

/// Validation of a model on one experiment.
struct ModelValidation {
  ChannelValidation angle, torque;
  /// Where the experiment has the chamber pressures (ExperimentData::tau_hydraulic_nm): the
  /// hydraulic torque's simulation and one-step prediction fits, reported and not judged (NaN
  /// without them, for a hydraulic torque that never changes, and for a diverged predictor).
  bool has_hydraulic = false;
  double hydraulic_fit_percent = std::numeric_limits<double>::quiet_NaN();
  double hydraulic_prediction_fit_percent = std::numeric_limits<double>::quiet_NaN();
  double process_scale = 1.0;  ///< the predictor's estimated process-noise factor (tunePredictorNoise)
  bool pass = false;
  std::vector<std::string> failures;  ///< one sentence per threshold missed
};

/// Simulates `model` on `data` and predicts it one step ahead (tunePredictorNoise), and judges
/// it against `thresholds`: each channel's simulation fit, the independence of its simulation
/// residual from the past excitation and the whiteness of its one-step prediction errors.
/// @throws std::invalid_argument for hydraulic torques that are not one per sample
[[nodiscard]] ModelValidation validateModel(const GreyModel& model, const ExperimentData& data,
                                            const ValidationThresholds& thresholds);

}  // namespace fullarm::identification
