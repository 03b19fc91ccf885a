#pragma once
/// @file
/// Linear stability and transparency analysis of the admittance controller on one DTS joint
/// (docs/analysis.md). Offline (allocates), not @rt.
///
/// The loop, sampled at the control period T:
///
///   plant (joint_linearization.hpp, ZOH-discretised) -> sensors sampled at t_k (potentiometer
///   q_k; load cell through its first-order analog filter, exact discretisation) -> the joint
///   controller of joint_controller.hpp in its linear region (sat(s/eps) = s/eps: Eq. (8); the
///   torque PID is linear anyway) with the virtual wall's torque tau_env = -K_w q - B_w qdot
///   (qdot the backward difference of the measured angle) -> `delay_samples` periods of
///   computation delay -> zero-order hold -> valve.
///
/// The controller's linear form is derived from the discrete-time law documented in
/// joint_controller.hpp (same order, same filters, same exact ZOH of Eq. (3)); a test checks it
/// against stepJointController() sample by sample. The passivity controller (nonlinear) is
/// off in the linear analysis; the gravity compensation enters as its slope g'(q).

#include <complex>
#include <vector>

#include "fullarm/controllers/gains.hpp"
#include "fullarm/design/joint_linearization.hpp"
#include "fullarm/design/lti.hpp"
#include "fullarm/design/margins.hpp"

namespace fullarm::design {

/// A virtual wall in contact (K_w = B_w = 0: free motion), in the controller's torque Eq. (4).
struct VirtualWall {
  double stiffness_nm_per_rad = 0.0;
  double damping_nms_per_rad = 0.0;
};

/// Everything about the loop that is not a gain.
struct LoopSetup {
  double control_period_s = 1e-3;
  int delay_samples = 1;             ///< whole periods between sampling and applying a command
  bool gravity_compensation = true;  ///< the controller subtracts the arm model's g(q)
  controllers::ControllerKind controller = controllers::ControllerKind::kAdmittance;
  FrictionLinearization friction = FrictionLinearization::kViscousOnly;
  double f_min_hz = 0.01;  ///< frequency grid from here to the Nyquist frequency
  int grid_points = 600;
};

/// The plant and its sensor chain discretised at the control period: states [joint states
/// (6), load-cell filter (1)], inputs [command, tau_user] (ZOH), outputs [q, tau_meas].
struct DiscreteJointPlant {
  JointLinearModel linear;  ///< the continuous model it came from
  StateSpace discrete;
  double sensor_filter_coefficient = 0.0;  ///< a = exp(-2 pi f_c T) of the load cell (0: none)
};

/// Discretises a linear joint and its sensors at `period_s`.
[[nodiscard]] DiscreteJointPlant discretizeJointPlant(const JointLinearModel& linear, const plant::JointParams& joint,
                                                      double period_s);

/// The linear form of stepJointController() (joint_controller.hpp) with the wall in its
/// tau_env input, as a discrete system: inputs [q, tau_load_cell] (deviations), output the
/// valve command u before the delay. Admittance states [theta_m, omega_m, q_prev, e_prev,
/// (e'_f), (tau_f)]; torque PID states [integral, tau_prev, q_prev, (tau_f)].
/// @throws core::ConfigError for invalid gains (validateJointGains).
[[nodiscard]] StateSpace controllerLinear(const controllers::JointGains& gains, controllers::ControllerKind kind,
                                          const VirtualWall& wall, double gravity_slope_nm_per_rad,
                                          const LoopSetup& setup);

/// Closed-loop frequency-domain results on the analysis grid.
struct FrequencyData {
  std::vector<double> frequency_hz;
  std::vector<std::complex<double>> loop;       ///< L at the valve command (negative-feedback convention)
  std::vector<std::complex<double>> impedance;  ///< rendered Z = tau_user / qd of the device [N m s/rad]
};

/// Results of analyzeJoint().
struct LinearChecks {
  LoopMargins margins;                  ///< of L at the valve command
  double spectral_radius = 0.0;         ///< discrete closed loop with the user's arm and the wall
  double device_spectral_radius = 0.0;  ///< closed loop of the device alone (no user)
  double open_loop_spectral_radius = 0.0;
  bool stable = false;  ///< spectral_radius < 1 (a free-position pole at 1 counts as stable)
  /// Saturation sector: min Re L > -1 (circle criterion for sat in [0, 1]) and no conditional
  /// stability: the loop scaled by every kappa of kSectorScales is stable too (which the circle
  /// criterion implies when the open loop is stable; checked explicitly because a joint without
  /// a restoring user spring has a slow open-loop pole at or just outside z = 1).
  bool sector_ok = false;
  bool low_gain_stable = false;     ///< the kSectorScales part of sector_ok
  bool passive = false;             ///< min Re Z >= 0 and the device loop stable
  double min_real_impedance = 0.0;  ///< min over the grid of Re Z [N m s/rad]
  double min_real_impedance_hz = 0.0;
  Eigen::VectorXcd closed_loop_poles;  ///< eigenvalues (z) of the closed loop
  /// Range of the factor on the controller's output gain (B_o/eps, or all PID gains) that keeps
  /// the closed loop stable: (lower, upper); the upper one is the predicted stability limit.
  double gain_scale_lower = 0.0;
  double gain_scale_upper = 0.0;
  FrequencyData frequency;
};

/// Loop-gain scales kappa at which the sector check requires stability (sat(s/eps) acts as a
/// gain kappa in (0, 1] on the linear loop).
inline constexpr double kSectorScales[] = {0.05, 0.1, 0.2, 0.35, 0.5, 0.7};

/// Stability tolerance for the free-position pole (see LinearChecks::stable).
inline constexpr double kMarginalPoleTolerance = 1e-7;

/// The whole analysis of one joint: `model.include_user` decides whether the loop analysis
/// couples the user's arm; the rendered impedance is always of the bare device.
/// @throws core::ConfigError for invalid gains; std::invalid_argument for a bad setup.
[[nodiscard]] LinearChecks analyzeJoint(const JointPlantModel& model, const OperatingPoint& op,
                                        const controllers::JointGains& gains, const VirtualWall& wall,
                                        const LoopSetup& setup);

/// A prepared joint (both discretisations), for repeated analyses with different gains.
struct PreparedJoint {
  JointPlantModel model;
  DiscreteJointPlant coupled;  ///< with the user's arm (if model.include_user)
  DiscreteJointPlant device;   ///< without
  LoopSetup setup;
};
[[nodiscard]] PreparedJoint prepareJoint(const JointPlantModel& model, const OperatingPoint& op,
                                         const LoopSetup& setup);
/// analyzeJoint() on a prepared joint; `with_frequency_data` false skips the stored responses,
/// `with_gain_limits` false skips the gain-scale bisection (both limits 0 then).
[[nodiscard]] LinearChecks analyzePrepared(const PreparedJoint& joint, const controllers::JointGains& gains,
                                           const VirtualWall& wall, bool with_frequency_data = true,
                                           bool with_gain_limits = true);

/// Spectral radius of the coupled closed loop.
[[nodiscard]] double closedLoopSpectralRadius(const PreparedJoint& joint, const controllers::JointGains& gains,
                                              const VirtualWall& wall);

/// Eigenvalues (z) of the coupled closed loop (device + the model's user, `wall` in the controller,
/// the setup's delay): the poles whose slowest oscillatory member coupled_stability.hpp judges.
[[nodiscard]] Eigen::VectorXcd closedLoopPoles(const PreparedJoint& joint, const controllers::JointGains& gains,
                                               const VirtualWall& wall);

/// The coupled closed loop itself (device + the model's user, `wall` in the controller, the setup's
/// delay register): states [plant (7), controller, delay], input the user's torque tau_user [N m]
/// (the plant's kInUserTorque column), outputs [q, applied command]. Its A has closedLoopPoles().
[[nodiscard]] StateSpace closedLoopSystem(const PreparedJoint& joint, const controllers::JointGains& gains,
                                          const VirtualWall& wall);

/// Rendered impedance of the device at w [rad/s] (first-harmonic model of the sampled loop:
/// aliases neglected; exact for the continuous paths).
[[nodiscard]] std::complex<double> renderedImpedance(const PreparedJoint& joint, const controllers::JointGains& gains,
                                                     const VirtualWall& wall, double w_radps);

/// Predicted stability limit of the wall stiffness for wall damping `damping`: the largest K_w
/// with spectral radius < 1 (coupled loop), by bisection in log K on [k_min, k_max].
/// Returns k_max if stable up to it, 0 if unstable at k_min.
[[nodiscard]] double wallStiffnessLimit(const PreparedJoint& joint, const controllers::JointGains& gains,
                                        double damping_nms_per_rad, double k_min = 1.0, double k_max = 1e6);

/// One point of a Z-width curve.
struct ZWidthPoint {
  double damping_nms_per_rad = 0.0;
  double max_stiffness_nm_per_rad = 0.0;  ///< largest stable K_w
};
/// The Z-width of the joint: wallStiffnessLimit() over `dampings`.
[[nodiscard]] std::vector<ZWidthPoint> jointZWidth(const PreparedJoint& joint, const controllers::JointGains& gains,
                                                   const std::vector<double>& dampings);

/// Colgate & Schenkel (1997) sampled-data passivity of a haptic device with physical damping b
/// (mass-damper) rendering a discrete position-to-force law H(z) through a ZOH at period T:
/// passive iff b > T / (2 (1 - cos wT)) Re{(1 - e^{-jwT}) H(e^{jwT})} for 0 <= w <= pi/T.
/// Returns the right-hand side maximised over a grid of `points` frequencies in (0, pi/T].
[[nodiscard]] double colgateRequiredDamping(const std::function<std::complex<double>(std::complex<double>)>& H,
                                            double period_s, int points = 4000);

/// Z-width of a mass-damper haptic device (damping b, period T) rendering a virtual wall
/// K + B (1 - z^-1)/T: the largest K that Colgate & Schenkel's condition allows for each B,
/// by bisection on colgateRequiredDamping(). Analytic answer: K = 2 (b - |B|) / T.
[[nodiscard]] std::vector<ZWidthPoint> massDamperZWidth(double device_damping_nms_per_rad, double period_s,
                                                        const std::vector<double>& wall_dampings);

}  // namespace fullarm::design
