#pragma once
/// @file
/// Grey-box output-error fit of one hydraulic joint in closed loop.
///
/// The model is the joint reduced to the groups the data can determine, with the structure of the
/// plant's valve and friction (docs/identification.md), in joint units:
///
///   tau_h' = K_h (a Q(u + u_0, tau_h) - w - c tau_h)              hydraulic torque D p_L   (I1)
///   Q(x, tau_h) = r(x + l) sqrt(1 - tau_h / tau_s) - r(l - x) sqrt(1 + tau_h / tau_s)
///   J w'   = tau_h - f(w) - tau_g - k_g (q - q_0)                  link                     (I2)
///   f(w)   = (tau_c + tau_st exp(-(w / w_s)^2)) tanh(w / w_eps) + b w
///   q'     = w
///   q_meas = q + q_off,   tau_meas = tau_h - f(w) + tau_off,   tau_hyd = tau_h
///
/// Q is the four-edge orifice law of a matched symmetric valve (the plant's H6 with H10's no-load
/// gain factored out): r the edge opening rounded over `edge_rounding_v` (H2), l the underlap, and
/// tau_s = D (p_s - p_r) the stall torque, all known from the plant's file. a = K_q / D is the
/// valve's flow gain as a joint speed per volt (amplifier gain x rated flow over the
/// displacement: one parameter), K_h = 4 beta D^2 / V_t the hydraulic stiffness (bulk modulus
/// over volume: one parameter), c = C_tl / D^2 the leakage, J the inertia, b, tau_c, tau_st
/// viscous, Coulomb and Stribeck friction (the plant's H7), tau_g the static load at the start
/// angle q_0 and k_g its known gradient, u_0 the valve null offset and q_off, tau_off the sensor
/// offsets. The valve command is delayed by d samples between the reading it was computed from
/// and the reading that shows its effect. With tau_s = 0, l = 0 and no rounding Q(x) = x, the
/// linearised valve.
///
/// The fit simulates the known closed loop (the logged hold law u = K (q_hold - q_meas) + r
/// driven by the logged excitation r) and minimises the output error on angle and torque, and,
/// where the chamber pressures were logged (hydraulicTorque in joint_groups.hpp), on the gap
/// tau_hyd - tau_meas between hydraulic torque and load cell, which is the friction (I12); each
/// channel normalised by its spread, over several experiments at once. Parameters are log-scaled
/// (signed offsets linear) inside bounds; a global stage samples the box at every delay, the best
/// candidates are polished by Levenberg-Marquardt with the exact forward sensitivities of the
/// discretised simulation (central differences selectable), and the delay is settled by
/// polishing its neighbours. Each experiment may have its own initial speed and hydraulic torque
/// estimated with the groups. Standard errors and correlations come from the Jacobian at the
/// optimum; directions whose singular value is negligible are named.

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
  kStribeck,      ///< tau_st, static minus Coulomb friction [N m]
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
  std::array<double, kGreyParams> value{0.5, 1.0e4, 1.0e-4, 0.05, 0.5, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0};
  int delay_samples = 1;
  double coulomb_smoothing_radps = 0.05;  ///< w_eps (fixed)
  double stribeck_velocity_radps = 0.05;  ///< w_s (fixed)
  /// Known valve structure (fixed, not fitted): the stall torque tau_s = D (p_s - p_r) of the
  /// orifice law (0: flow independent of the load), the underlap l of each metering edge and the
  /// edges' rounding, both in volts of command (0: critically centred, sharp edges).
  double stall_torque_nm = 0.0;
  double underlap_v = 0.0;
  double edge_rounding_v = 0.0;
  /// Known gradient k_g of the static load about the start angle [N m/rad] (gravity; fixed).
  double load_gradient_nm_per_rad = 0.0;
  /// Known channel dynamics (fixed, not fitted; 0 = none): the servovalve spool as a second-order
  /// lag of the command (natural frequency, damping ratio) and the load cell's first-order
  /// low-pass, which, as in the plant's sensor model, filters the sampled torque:
  /// y_k = a y_{k-1} + (1 - a) tau_cell(t_k), a = exp(-2 pi f_c T).
  double spool_hz = 0.0;
  double spool_damping = 0.7;
  double torque_filter_hz = 0.0;
};

/// One experiment as the fit sees it.
struct ExperimentData {
  double sample_period_s = 1.0e-3;
  std::vector<double> excitation_v, command_v, q_rad, tau_nm;
  /// The hydraulic torque the chamber pressures give [N m], one per sample (empty: no pressures
  /// were logged; hydraulicTorque in joint_groups.hpp fills it from a log that has them).
  std::vector<double> tau_hydraulic_nm;
  double hold_gain_v_per_rad = 0.0;  ///< K of the hold law
  double hold_rad = 0.0;             ///< q_hold of the hold law
};

/// An experiment from a log (kExperimentColumns), with the hold law u - r = K (q_hold - q)
/// recovered from the log by least squares.
/// @throws std::invalid_argument when the time step is not uniform or the log has no hold law
///   (the command does not depend on the angle)
[[nodiscard]] ExperimentData experimentFromLog(const SignalTable& log);

/// The state an experiment's simulation starts from beyond its first logged angle: the joint's
/// speed and the hydraulic torque's excess over the static load tau_g (both zero: at rest).
struct InitialState {
  double speed_radps = 0.0;
  double torque_offset_nm = 0.0;
};

/// Sensitivity directions beyond the GreyParam indices: an experiment's initial speed and
/// hydraulic torque offset (InitialState).
inline constexpr int kInitialSpeed = kGreyParams;
inline constexpr int kInitialTorqueOffset = kGreyParams + 1;

/// Name of an InitialState member with its unit ("initial_speed_radps", ...).
[[nodiscard]] const char* initialStateName(int direction) noexcept;

/// The model's outputs over an experiment: the readings of angle, load cell and hydraulic torque
/// (the state tau_h, as pressure transducers would give it), each delayed as the readings are.
struct Simulation {
  std::vector<double> q_rad, tau_nm, command_v, tau_hydraulic_nm;
  bool ok = true;  ///< false when the state diverged (non-finite or beyond 1e3 rad)
};

/// Valve load flow Q(x, tau_h) of (I1) in volts of command: the orifice law with `model`'s stall
/// torque, underlap and edge rounding (x itself for a linearised valve).
[[nodiscard]] double valveLoadFlow(const GreyModel& model, double x_v, double tau_h_nm) noexcept;

/// Simulates the closed loop of `data` (its hold law and excitation) with `model`, from the state
/// reading d shows (d the delay; the first d readings, of earlier states, and the commands the
/// hold law computed from them are taken as logged; without logged torques, the first state's
/// torque reading), at its angle with `initial`'s speed and
/// hydraulic torque tau_g + offset (by default at rest),
/// the load-cell filter settled and the spool where the valve's flow feeds that speed and the
/// leakage (at rest: balances the leakage under the static load); 4 RK4 sub-steps per sample (8
/// with a spool), the command held over each sample, through the spool and the load-cell filter
/// when the model has them.
[[nodiscard]] Simulation simulateClosedLoop(const GreyModel& model, const ExperimentData& data,
                                            const InitialState& initial = {});

/// A simulation with its forward sensitivities: column j holds the derivative of every logged
/// sample's output with respect to `directions[j]` (in that parameter's own unit).
struct SimulationSensitivity {
  Simulation simulation;
  Eigen::MatrixXd q_rad;             ///< samples x directions [rad per unit]
  Eigen::MatrixXd tau_nm;            ///< samples x directions [N m per unit]
  Eigen::MatrixXd tau_hydraulic_nm;  ///< samples x directions [N m per unit]
};

/// The exact derivatives of simulateClosedLoop's outputs (the discretised simulation: every RK4
/// sub-step, the hold law through the delayed reading, the initial state's dependence on the
/// parameters) with respect to `directions` (GreyParam indices, kInitialSpeed,
/// kInitialTorqueOffset), propagated forward with the state in dual numbers (I10). The delay is
/// an integer and is not a direction. Where the model is not differentiable the one-sided
/// derivative of the branch taken is given (an orifice edge past its full pressure drop); a
/// diverged run (`simulation.ok` false) has zero sensitivities from the divergence on.
/// @throws std::invalid_argument for a direction that is not a parameter
[[nodiscard]] SimulationSensitivity simulateSensitivities(const GreyModel& model, const ExperimentData& data,
                                                          const InitialState& initial,
                                                          const std::vector<int>& directions);

/// Noise levels of the one-step-ahead predictor's Kalman filter (predictOneStep), as standard
/// deviations.
struct PredictorNoise {
  double angle_rad = 3.0e-4;  ///< of the angle reading (noise and quantisation)
  double torque_nm = 0.1;     ///< of the load-cell reading, white at the reading (its quantisation)
  /// Of the load cell's analog noise ahead of its filter (0: none). Through the filter it is
  /// coloured, so the filter carries it as process noise on its state, (1 - a) sigma per sample
  /// with a = exp(-2 pi f_c T); a model without the filter adds it to the reading's.
  double torque_cell_nm = 0.0;
  double process_torque_nm = 0.2;      ///< per sample, on the hydraulic torque: what the model leaves out
  double process_speed_radps = 0.001;  ///< per sample, on the speed
};

/// One-step-ahead prediction of `data`'s readings by `model` (MATLAB's `compare` with horizon 1):
/// an extended Kalman filter on the reduced model, linearised at every sample by finite
/// differences of its one-sample step, estimates the unmeasured speed, hydraulic torque, spool
/// and filter states from the angle and load-cell readings up to the previous sample, and each
/// reading is predicted from that estimate one step ahead. The command is the hold law on the
/// measured angle plus the excitation, the same law the simulation closes on its own reading; with
/// a delay of d samples reading k shows the state of sample k - d. The filter starts from the
/// simulation's initial state at rest (at the angle reading d shows), so the first d readings
/// (before any reading reaches the filter) are that state's readings, as in the simulation.
/// The hydraulic torque is predicted from the same estimate (the chamber pressures, where logged,
/// are not among the filter's readings).
/// @throws std::invalid_argument for a non-positive noise level (the cell's may be zero)
[[nodiscard]] Simulation predictOneStep(const GreyModel& model, const ExperimentData& data,
                                        const PredictorNoise& noise);

/// One parameter's treatment in the fit.
struct ParamSpec {
  bool free = true;
  double min = 0.0;  ///< bounds (positive for log-scaled parameters)
  double max = 0.0;
  bool log_scaled = true;
};

/// How the polish gets the residuals' Jacobian.
enum class JacobianMethod {
  kSensitivities,      ///< forward sensitivities of the simulation (simulateSensitivities): exact
  kCentralDifferences  ///< central differences of the simulation, two runs per parameter
};

/// Settings of the fit.
struct FitOptions {
  std::array<ParamSpec, kGreyParams> params{};
  /// Each experiment's initial speed and hydraulic torque offset (InitialState; linear scaling,
  /// bounds containing 0): free = estimated per experiment with the groups, fixed = at rest.
  ParamSpec initial_speed{false, -1.0, 1.0, false};
  ParamSpec initial_torque_offset{false, -20.0, 20.0, false};
  JacobianMethod jacobian = JacobianMethod::kSensitivities;
  /// The global stage tries every delay 0 .. this; the cost counts from this reading on.
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

/// Bounds spanning x`factor` either side of `model`'s positive values (a group at zero, such as
/// a Stribeck friction the model leaves out, is fixed), the load free in +-20 N m, offsets fixed;
/// a sensible default around a nominal model.
[[nodiscard]] FitOptions defaultFitOptions(const GreyModel& nominal, double factor = 3.0);

/// Result of a fit.
struct FitResult {
  GreyModel model;
  double cost = 0.0;  ///< half the sum of squared normalised residuals (from reading max_delay_samples on)
  std::array<double, kGreyParams> standard_error{};  ///< in the parameter's unit (0 when fixed)
  Eigen::MatrixXd correlation;                       ///< of the free parameters, in order
  std::vector<int> free_params;                      ///< indices of the free parameters
  std::vector<std::string> unidentifiable;           ///< directions the data cannot determine
  /// Each experiment's initial state (at rest where fixed) and its standard errors.
  std::vector<InitialState> initial_states;
  std::vector<InitialState> initial_state_standard_error;
  int evaluations = 0;              ///< closed-loop simulations run (values only)
  int sensitivity_evaluations = 0;  ///< simulations run with sensitivities (up to 4 directions each)
  double global_seconds = 0.0;      ///< wall time of the global stage
  double polish_seconds = 0.0;      ///< wall time of the polish
};

/// Fits the model to the experiments jointly, starting from `start` (the global stage includes it).
/// Free initial states start, at every point of the global stage, from the data: the speed
/// from the slope of ten angles from reading d on (the reading that shows the first state) and
/// the torque offset from load-cell reading d, each clamped into its bounds.
/// The cost counts each experiment's residuals from reading `max_delay_samples` on, at every
/// delay: a simulation with a delay of d takes its first d readings as logged, and a cost over all
/// the readings it simulates would favour longer delays.
/// @throws std::invalid_argument for no experiments, hydraulic torques that are not one finite value
///   per sample, bounds that do not hold the start, or
///   non-positive bounds of a log-scaled parameter, or initial-state bounds that do not hold 0,
///   or an experiment with no more samples than max_delay_samples plus the fit's coordinates
[[nodiscard]] FitResult fitGreyModel(const std::vector<ExperimentData>& experiments, const GreyModel& start,
                                     const FitOptions& options);

/// Fit percentage 100 (1 - |y - y_hat| / |y - mean(y)|) (MATLAB's `compare`).
[[nodiscard]] double fitPercent(const std::vector<double>& measured, const std::vector<double>& modelled);

}  // namespace fullarm::identification
