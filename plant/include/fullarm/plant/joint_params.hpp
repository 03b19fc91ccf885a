#pragma once
/// @file
/// Parameters of one servovalve-actuated hydraulic joint of the DTS master arm
/// (docs/plant.md; equations in docs/sources.md, Plant 1.1-1.6). SI units throughout.
///
/// A JointParams is built by the YAML loader (plant_config.hpp) or in code, then checked
/// once with validateJointParams(); after that it is treated as constant.

#include <string>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::plant {

/// What the per-joint command of ArmPlant::step() means.
enum class InputMode {
  kValveVoltage,  ///< command = valve drive voltage [V] through the amplifier gain
  kTorqueLoop,    ///< command = desired torque [N m] into the analog torque loop of the joint card
};

/// How the joint is moved.
enum class ActuatorKind {
  kRotaryVane,   ///< rotary vane: torque = D (p_a - p_b)
  kCylinder,     ///< linear cylinder on a lever (geometry from the arm model's ActuatorGeometry)
  kIdealTorque,  ///< no hydraulics: the command is the actuator torque [N m] (for verification)
};

/// Second-order servovalve spool and its amplifier (docs/sources.md, Plant 1.1).
struct ValveParams {
  double natural_frequency_hz = 150.0;  ///< spool natural frequency
  double damping_ratio = 0.7;           ///< spool damping ratio
  double amplifier_gain_per_v = 0.1;    ///< normalised spool command per volt (1 = full opening)
  double spool_stroke_m = 2.5e-4;       ///< spool displacement at normalised opening 1
  /// Flow through one fully open metering edge at the rated pressure drop across that edge.
  double rated_flow_m3ps = 1.0e-5;
  double rated_pressure_drop_pa = 3.5e6;  ///< per metering edge (Moog: 70 bar over two edges)
  /// Laps of the four metering edges P->A, P->B, A->T, B->T: positive = overlap (dead band),
  /// negative = underlap (null leakage). docs/sources.md, Plant 1.2 (Hopsan convention).
  double lap_pa_m = 0.0;
  double lap_pb_m = 0.0;
  double lap_at_m = 0.0;
  double lap_bt_m = 0.0;
  /// Half-width of the C1 rounding of each edge opening max(x - lap, 0) (keeps the Jacobian
  /// continuous); an edge lapped by more than this is exactly closed at null.
  double edge_rounding_m = 5.0e-7;
  /// Pressure drop below which the signed square root of the orifice law is replaced by a
  /// C1 odd cubic (docs/sources.md, Plant 1.2, "numerical must-have").
  double linear_region_pa = 1.0e5;
};

/// Oil (docs/sources.md, Plant 1.3).
struct FluidParams {
  double oil_bulk_modulus_pa = 1.4e9;          ///< pure-oil bulk modulus
  double air_fraction = 0.0;                   ///< entrained air volume fraction at atmospheric pressure
  double polytropic_index = 1.4;               ///< of the entrained air
  double atmospheric_pressure_pa = 1.01325e5;  ///< absolute atmospheric pressure
};

/// Chambers, lines and leakage.
struct ChamberParams {
  double dead_volume_a_m3 = 1.5e-6;           ///< chamber A volume at its end of stroke, incl. lines and manifold
  double dead_volume_b_m3 = 1.5e-6;           ///< chamber B volume at its end of stroke, incl. lines and manifold
  double internal_leakage_m3ps_per_pa = 0.0;  ///< cross-piston leakage Q_i = C_i (p_a - p_b)
  double external_leakage_m3ps_per_pa = 0.0;  ///< to drain, per chamber: Q_e = C_e p (gauge)
  /// Conductance of the anti-cavitation and relief check valves of each chamber (return -> chamber
  /// below p_r, chamber -> supply above p_s); 0 = none. Q = G ramp(p - p_s) etc. [m^3/s/Pa]
  double check_valve_conductance_m3ps_per_pa = 0.0;
};

/// Actuator. Rotary vane uses displacement_m3_per_rad; a cylinder uses the two piston areas
/// and the lever of the arm model.
struct ActuatorParams {
  ActuatorKind kind = ActuatorKind::kRotaryVane;
  double displacement_m3_per_rad = 2.5e-6;  ///< rotary vane
  double piston_area_a_m2 = 0.0;            ///< cylinder cap side (extending the cylinder fills A)
  double piston_area_b_m2 = 0.0;            ///< cylinder rod side
  arm::ActuatorGeometry lever{};            ///< cylinder lever (copied from the arm model)
  double inertia_kgm2 = 0.0;                ///< actuator-side inertia between the actuator and the load cell
};

/// Coulomb + viscous + Stribeck friction with a tanh-smoothed sign (docs/sources.md, Plant 1.5),
/// acting on the actuator side of the load cell.
struct FrictionParams {
  double coulomb_nm = 0.0;
  double static_nm = 0.0;  ///< breakaway (>= coulomb_nm)
  double stribeck_velocity_radps = 0.05;
  double viscous_nms_per_rad = 0.0;
  double smoothing_velocity_radps = 1e-3;  ///< tanh(omega / this) replaces sign(omega)
};

/// Penalty hard stops at the joint limits (Hunt-Crossley form tau = -K pen (1 + c pen_rate),
/// dissipative: c K pen pen_rate^2 >= 0), on the actuator side of the load cell.
struct HardStopParams {
  double stiffness_nm_per_rad = 2.0e5;
  double damping_s_per_rad = 10.0;  ///< c of the Hunt-Crossley law [s/rad]
};

/// Analog torque loop of the joint card (AJC): valve voltage = gain (tau_desired - tau_cell).
struct TorqueLoopParams {
  double gain_v_per_nm = 0.5;
};

/// Sensor imperfections of one joint (the calibration comes from the arm model).
struct SensorNoiseParams {
  double angle_noise_rad = 0.0;   ///< standard deviation of potentiometer noise before the ADC
  double torque_noise_nm = 0.0;   ///< standard deviation of load-cell noise before the filter
  double torque_bias_nm = 0.0;    ///< load-cell offset
  double torque_filter_hz = 0.0;  ///< first-order analog low-pass of the load cell; 0 = none
  /// Chamber pressure transducers (gauge, 0 .. full scale through an ADC of `pressure_bits`):
  /// full scale 0 = the joint has none (the DTS master's joints have none; a test rig's or a
  /// simulated joint's may).
  double pressure_full_scale_pa = 0.0;
  int pressure_bits = 12;          ///< ADC resolution of the pressure transducers
  double pressure_noise_pa = 0.0;  ///< standard deviation of their noise before the ADC
};

/// Everything about one hydraulic joint. Constant after validateJointParams().
struct JointParams {
  std::string name;  ///< joint name in the arm model, e.g. "R_EB"
  InputMode input_mode = InputMode::kValveVoltage;
  double supply_pressure_pa = 20.7e6;
  double return_pressure_pa = 0.3e6;
  ValveParams valve{};
  FluidParams fluid{};
  ChamberParams chambers{};
  ActuatorParams actuator{};
  FrictionParams friction{};
  HardStopParams hard_stop{};
  TorqueLoopParams torque_loop{};
  SensorNoiseParams sensor_noise{};
  arm::PotentiometerCalibration potentiometer{};  ///< from the arm model
  arm::TorqueSensorCalibration torque_sensor{};   ///< from the arm model
  double min_rad = -1.0;                          ///< joint limit (hard stop), from the arm model
  double max_rad = 1.0;                           ///< joint limit (hard stop), from the arm model
};

/// Checks ranges and consistency (positive volumes and gains, supply > return, cylinder lever
/// monotonic over the joint range, ...).
/// @param key_path prefix of the key paths in the error, e.g. "joints[3]"
/// @throws core::ConfigError naming `file`, the key path, the value and what was expected.
void validateJointParams(const JointParams& p, const std::string& file = {}, const std::string& key_path = {});

}  // namespace fullarm::plant
