#pragma once
/// @file
/// Grey-box output-error fit of one hydraulic joint in closed loop.
///
/// The model is the joint reduced to the groups the data can determine (Merritt's linearised
/// valve-cylinder with the load, docs/identification.md), in joint units:
///
///   tau_h' = K_h (a (u + u_0) - w - c tau_h)                 hydraulic torque D p_L   (I1)
///   J w'   = tau_h - b w - tau_c tanh(w / w_eps) - tau_g     link                     (I2)
///   q'     = w
///   q_meas = q + q_off,   tau_meas = tau_h - b w - tau_c tanh(w / w_eps) + tau_off
///
/// a = K_q / D is the valve's flow gain as a joint speed per volt (amplifier gain x rated flow
/// over the displacement: one parameter), K_h = 4 beta D^2 / V_t the hydraulic stiffness (bulk
/// modulus over volume: one parameter), c = C_tl / D^2 the leakage, J the inertia, b, tau_c
/// viscous and Coulomb friction, tau_g the static load, u_0 the valve null offset and q_off,
/// tau_off the sensor offsets. The valve command is delayed by d samples between the reading it
/// was computed from and the reading that shows its effect.
///
/// The fit simulates the known closed loop (the logged hold law u = K (q_hold - q_meas) + r
/// driven by the logged excitation r) and minimises the output error on angle and torque,
/// each normalised by its spread, over several experiments at once. Parameters are log-scaled
/// (signed offsets linear) inside bounds; a global stage samples the box at every delay, the best
/// candidates are polished by Levenberg-Marquardt with a central-difference Jacobian, and the
/// delay is settled by polishing its neighbours. Standard errors and correlations come from the
/// Jacobian at the optimum; directions whose singular value is negligible are named.

#include <array>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fullarm/identification/signal_csv.hpp"

namespace fullarm::identification {

/// The parameters of the reduced joint model.
enum GreyParam : int {
  kFlowGain = 0,  ///< a [rad/s/V]
  kStiffness,     ///< K_h [N m/rad]
  kLeakage,       ///< c [rad/s/(N m)]
  kInertia,       ///< J [kg m^2]
  kViscous,       ///< b [N m s/rad]
  kCoulomb,       ///< tau_c [N m]
  kLoadTorque,    ///< tau_g [N m]
  kValveOffset,   ///< u_0 [V]
  kAngleOffset,   ///< q_off [rad]
  kTorqueOffset,  ///< tau_off [N m]
  kGreyParams
};

/// Name of a parameter with its unit ("flow_gain_radps_per_v", ...), as in the YAML files.
[[nodiscard]] const char* greyParamName(int index) noexcept;

/// Values of the reduced model.
struct GreyModel {
  std::array<double, kGreyParams> value{0.5, 1.0e4, 1.0e-4, 0.05, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0};
  int delay_samples = 1;
  double coulomb_smoothing_radps = 0.05;  ///< w_eps (fixed)
  /// Known channel dynamics (fixed, not fitted; 0 = none): the servovalve spool as a second-order
  /// lag of the command (natural frequency, damping ratio) and the load cell's first-order
  /// analog low-pass.
  double spool_hz = 0.0;
  double spool_damping = 0.7;
  double torque_filter_hz = 0.0;
};

/// One experiment as the fit sees it.
struct ExperimentData {
  double sample_period_s = 1.0e-3;
  std::vector<double> excitation_v, command_v, q_rad, tau_nm;
  double hold_gain_v_per_rad = 0.0;  ///< K of the hold law
  double hold_rad = 0.0;             ///< q_hold of the hold law
};

/// An experiment from a log (kExperimentColumns), with the hold law u - r = K (q_hold - q)
/// recovered from the log by least squares.
/// @throws std::invalid_argument when the time step is not uniform or the log has no hold law
///   (the command does not depend on the angle)
[[nodiscard]] ExperimentData experimentFromLog(const SignalTable& log);

/// The model's outputs over an experiment.
struct Simulation {
  std::vector<double> q_rad, tau_nm, command_v;
  bool ok = true;  ///< false when the state diverged (non-finite or beyond 1e3 rad)
};

/// Simulates the closed loop of `data` (its hold law and excitation) with `model`, from rest at
/// the first logged angle; 4 RK4 sub-steps per sample (8 with a spool), the command held over
/// each sample, through the spool and the load-cell filter when the model has them.
[[nodiscard]] Simulation simulateClosedLoop(const GreyModel& model, const ExperimentData& data);

/// One parameter's treatment in the fit.
struct ParamSpec {
  bool free = true;
  double min = 0.0;  ///< bounds (positive for log-scaled parameters)
  double max = 0.0;
  bool log_scaled = true;
};

/// Settings of the fit.
struct FitOptions {
  std::array<ParamSpec, kGreyParams> params{};
  int max_delay_samples = 4;
  int global_samples = 200;     ///< points of the global stage (per delay)
  int polished_candidates = 3;  ///< best global points polished
  int max_iterations = 60;      ///< Levenberg-Marquardt iterations per polish
  std::uint64_t seed = 1;       ///< the global stage's sampling
  /// Threads running the simulations (the global stage's points, the Jacobian's columns); the
  /// result does not depend on it.
  int threads = 1;
  /// Progress lines while fitting (nullptr: silent).
  std::function<void(const std::string&)> progress;
};

/// Bounds spanning x`factor` either side of `model`'s positive values, offsets free in +-`offset`
/// (sensor offsets fixed at zero); a sensible default around a nominal model.
[[nodiscard]] FitOptions defaultFitOptions(const GreyModel& nominal, double factor = 3.0);

/// Result of a fit.
struct FitResult {
  GreyModel model;
  double cost = 0.0;                                 ///< half the sum of squared normalised residuals
  std::array<double, kGreyParams> standard_error{};  ///< in the parameter's unit (0 when fixed)
  Eigen::MatrixXd correlation;                       ///< of the free parameters, in order
  std::vector<int> free_params;                      ///< indices of the free parameters
  std::vector<std::string> unidentifiable;           ///< directions the data cannot determine
  int evaluations = 0;                               ///< closed-loop simulations run
  double global_seconds = 0.0;                       ///< wall time of the global stage
  double polish_seconds = 0.0;                       ///< wall time of the polish
};

/// Fits the model to the experiments jointly, starting from `start` (the global stage includes it).
/// @throws std::invalid_argument for no experiments, bounds that do not hold the start, or
///   non-positive bounds of a log-scaled parameter
[[nodiscard]] FitResult fitGreyModel(const std::vector<ExperimentData>& experiments, const GreyModel& start,
                                     const FitOptions& options);

/// Fit percentage 100 (1 - |y - y_hat| / |y - mean(y)|) (MATLAB's `compare`).
[[nodiscard]] double fitPercent(const std::vector<double>& measured, const std::vector<double>& modelled);

}  // namespace fullarm::identification
