#pragma once
/// @file
/// Controller parameters of the DTS master arm, per joint, and their strict YAML loader
/// (config/dts_gains.yaml; schema in docs/controllers.md).
///
/// Symbols follow §3.3 of the DTS paper: the impedance model J_m, B_m, K_m (Eq. 3), the sliding
/// surface slope lambda (Eq. 6), the valve bound B_o and the boundary layer epsilon (Eq. 7).
/// A JointGains is built by the loader or in code, checked once with validateJointGains(), and
/// treated as constant afterwards.

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::controllers {

/// Which control law drives the valves.
enum class ControllerKind {
  kAdmittance,  ///< the paper's impedance model + sliding-mode position loop (Eq. 3-7)
  kTorquePid,   ///< the "simple torque controller" baseline: PID on the Eq. (4) torque
};

/// Impedance model of Eq. (3): J_m theta_m'' + B_m theta_m' + K_m (theta_m - theta_d) = tau.
struct ImpedanceParams {
  double inertia_kgm2 = 0.05;          ///< J_m > 0
  double damping_nms_per_rad = 2.0;    ///< B_m >= 0
  double stiffness_nm_per_rad = 20.0;  ///< K_m > 0
};

/// Sliding-mode position loop of Eq. (6)-(7): s = e' + lambda e, u = B_o sat(s / eps).
/// In the continuous (linear) region u = (B_o / eps)(e' + lambda e), a PD law (Eq. 8).
struct SlidingModeParams {
  double lambda_per_s = 20.0;         ///< lambda > 0: slope of the sliding surface [1/s]
  double valve_bound_v = 5.0;         ///< B_o > 0: largest valve command of the law [V]
  double boundary_layer_radps = 0.5;  ///< eps > 0: width of the saturation's linear region [rad/s]
};

/// The "simple torque controller" of §3.3: valve command = kp tau + ki int(tau) + kd tau',
/// tau the Eq. (4) torque (driven to zero in free space).
struct TorquePidParams {
  double kp_v_per_nm = 0.1;       ///< >= 0
  double ki_v_per_nms = 0.0;      ///< >= 0 [V / (N m s)]
  double kd_vs_per_nm = 0.0;      ///< >= 0 [V s / N m]
  double integral_limit_v = 2.0;  ///< >= 0: anti-windup clamp of the integral term [V]
};

/// Hannaford-Ryu time-domain passivity observer / controller on the user's port of the joint
/// (effort: estimated user torque, flow: joint velocity).
struct PassivityParams {
  bool enabled = false;                      ///< controller on; the observer always runs and logs
  double max_damping_nms_per_rad = 50.0;     ///< > 0: cap on the added damping alpha
  double velocity_threshold_radps = 1.0e-3;  ///< >= 0: no damping added below this speed
};

/// Everything the controllers need for one joint. Constant after validateJointGains().
struct JointGains {
  std::string name;  ///< arm joint name, e.g. "R_EB"
  ImpedanceParams impedance{};
  SlidingModeParams sliding_mode{};
  TorquePidParams torque_pid{};
  PassivityParams passivity{};
  /// First-order low-pass on the measured torque, cutoff [Hz]; 0 = no filter.
  double torque_filter_hz = 0.0;
  /// First-order low-pass on the position-error rate e' of Eq. (6), cutoff [Hz]; 0 = none.
  double error_rate_filter_hz = 0.0;
  /// Hard limit on the valve command of either controller [V] (> 0, >= B_o).
  double valve_limit_v = 10.0;
};

/// A whole gains file.
struct GainsConfig {
  std::filesystem::path source;  ///< file it was read from (empty if built in code)
  ControllerKind controller = ControllerKind::kAdmittance;
  double control_period_s = 1.0e-3;  ///< the rate the gains were designed for (> 0)
  std::vector<JointGains> joints;    ///< in the order of the file; names unique, arm joints only
};

/// Checks ranges: J_m > 0, B_m >= 0, K_m > 0, lambda > 0, B_o > 0, eps > 0, PID gains >= 0,
/// filter cutoffs >= 0 and below the Nyquist frequency of `control_period_s`, valve limit > 0
/// and >= B_o, passivity cap > 0; every value finite.
/// @param key_path prefix of key paths in the error, e.g. "joints[3]"
/// @throws core::ConfigError naming `file`, the key path, the value and what was expected.
void validateJointGains(const JointGains& g, double control_period_s, const std::string& file = {},
                        const std::string& key_path = {});

/// Loads and validates a gains file for `model` (strict: missing and unknown keys are errors;
/// joint names must be arm joints of `model`, each at most once).
/// @throws core::ConfigError naming the file, line, key path and what was expected.
[[nodiscard]] GainsConfig loadGainsConfig(const std::filesystem::path& file, const arm::ArmModel& model);

/// Parses gains YAML text; `source` names it in errors. @throws core::ConfigError
[[nodiscard]] GainsConfig parseGainsConfig(std::string_view yaml_text, const std::filesystem::path& source,
                                           const arm::ArmModel& model);

/// The YAML text of `config` in the schema loadGainsConfig reads (round-trips exactly: every
/// number is written with 17 significant digits). For `fullarm tune` output.
[[nodiscard]] std::string formatGainsYaml(const GainsConfig& config);

/// $FULLARM_CONFIG_DIR/dts_gains.yaml if set, else the source-tree or installed config folder.
[[nodiscard]] std::filesystem::path defaultGainsConfigPath();

/// $FULLARM_CONFIG_DIR/dts_tune_start.yaml if set, else the source-tree or installed config
/// folder: the fixed starting gains of `fullarm tune` (docs/analysis.md, "Start"), so that the
/// tune's result does not depend on the gains file it writes (tune on the default plant
/// reproduces dts_gains.yaml).
[[nodiscard]] std::filesystem::path defaultTuneStartGainsPath();

/// Index in config.joints of the joint called `name` (model name "R_EB" or short name "EB").
/// @throws core::ConfigError listing the known names when there is no such joint.
[[nodiscard]] int findGainsJoint(const GainsConfig& config, std::string_view name);

/// "admittance" / "torque_pid".
[[nodiscard]] std::string_view controllerKindName(ControllerKind kind) noexcept;

}  // namespace fullarm::controllers
