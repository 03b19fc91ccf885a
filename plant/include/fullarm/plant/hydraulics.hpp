#pragma once
/// @file
/// The hydraulic joint equations as free functions (all @rt: noexcept, no allocation).
/// Equation numbers "(H1)".."(H12)" are listed in docs/plant.md and reports/equations.md.

#include "fullarm/plant/joint_params.hpp"

namespace fullarm::plant {

/// Value and derivative of a scalar function.
struct ValueSlope {
  double value = 0.0;
  double slope = 0.0;
};

/// (H1) C1 regularised signed square root: sign(x) sqrt(|x|) for |x| >= x0, and the odd cubic
/// (5/4 x - x^3 / (4 x0^2)) / sqrt(x0) below, which matches value and slope at |x| = x0.
/// @param x pressure drop [Pa]; @param x0 transition [Pa] (> 0). Returns sqrt(Pa) and its slope.
/// @rt
[[nodiscard]] ValueSlope regularizedSignedSqrt(double x, double x0) noexcept;

/// (H2) C1 rounded ramp max(s, 0): 0 below -w, (s + w)^2 / (4 w) on [-w, w], s above w.
/// @rt
[[nodiscard]] ValueSlope roundedRamp(double s, double w) noexcept;

/// (H3) Effective bulk modulus with entrained air (Simscape / MapleSim form; docs/sources.md, Plant
/// 1.3): E = E_l [1 + a (p_atm/(p_atm+p))^(1/n)] / [1 + a p_atm^(1/n) E_l / (n (p_atm+p)^((n+1)/n))],
/// p gauge [Pa]. With air_fraction 0 it is the oil modulus. Pressures below 0.9 vacuum
/// are clamped inside the formula.
/// @rt
[[nodiscard]] ValueSlope effectiveBulkModulus(const FluidParams& f, double p_gauge_pa) noexcept;
/// (H3) with the constant p_atm^(1/n) precomputed by airRoot(f) (one pow() less per call). @rt
[[nodiscard]] ValueSlope effectiveBulkModulus(const FluidParams& f, double p_gauge_pa, double air_root) noexcept;
/// p_atm^(1/n) of (H3). @rt
[[nodiscard]] double airRoot(const FluidParams& f) noexcept;

/// Actuator stroke coordinate s(q) and its derivatives: for a rotary vane s = q [rad] with
/// area D [m^3/rad]; for a cylinder s = L(q) [m] (cylinder length) with area A [m^2].
struct ActuatorKinematics {
  double stroke = 0.0;       ///< s(q)
  double ratio = 1.0;        ///< ds/dq: 1 (vane) or the moment arm R(q) [m]
  double ratio_slope = 0.0;  ///< d2s/dq2
};

/// (H4) Stroke, moment arm and its slope at q (cylinder: L = sqrt(r^2 + d^2 - 2 r d cos phi),
/// R = r d sin(phi) / L; docs/sources.md, Plant 1.4 and arm/actuator.hpp).
/// @rt
[[nodiscard]] ActuatorKinematics actuatorKinematics(const ActuatorParams& a, double q_rad) noexcept;

/// Sine and cosine of an angle, computed once and shared (the joint angle's by the arm kinematics
/// and the cylinder geometry).
struct SinCos {
  double sin = 0.0;
  double cos = 1.0;
};
/// sin and cos of a cylinder's lever angle offset (phi = q + offset); {0, 1} for other actuators.
[[nodiscard]] SinCos leverOffsetSinCos(const ActuatorParams& a) noexcept;
/// actuatorKinematics with sin q, cos q given and the lever offset's from leverOffsetSinCos: no
/// trigonometric call (sin phi, cos phi by angle addition; equal to the other form to rounding). @rt
[[nodiscard]] ActuatorKinematics actuatorKinematics(const ActuatorParams& a, double q_rad, SinCos q,
                                                    SinCos lever_offset) noexcept;

/// Effective areas of chambers A and B: D (vane) or the piston areas (cylinder).
/// @rt
[[nodiscard]] double areaA(const ActuatorParams& a) noexcept;
/// @copydoc areaA
[[nodiscard]] double areaB(const ActuatorParams& a) noexcept;

/// Stroke at the joint limits (min, max of s over [min_rad, max_rad]; s is monotonic there).
struct StrokeRange {
  double s_min = 0.0;
  double s_max = 0.0;
  bool increasing = true;  ///< ds/dq > 0 over the range
};
/// @rt
[[nodiscard]] StrokeRange strokeRange(const JointParams& p) noexcept;

/// (H5) Chamber volumes [m^3]: V_a = V_a0 + A_a (s - s_min) (s increasing in q), V_b = V_b0 +
/// A_b (s_max - s); mirrored when s decreases with q so chamber A always drives q positive.
struct ChamberVolumes {
  double v_a_m3 = 0.0;
  double v_b_m3 = 0.0;
  double dva_dq = 0.0;  ///< dV_a/dq [m^3/rad]
  double dvb_dq = 0.0;  ///< dV_b/dq [m^3/rad]
  double d2va_dq2 = 0.0;
  double d2vb_dq2 = 0.0;
};
/// @rt
[[nodiscard]] ChamberVolumes chamberVolumes(const JointParams& p, const StrokeRange& range, double q_rad) noexcept;
/// chamberVolumes with sin q, cos q given (see the actuatorKinematics overload). @rt
[[nodiscard]] ChamberVolumes chamberVolumes(const JointParams& p, const StrokeRange& range, double q_rad, SinCos q,
                                            SinCos lever_offset) noexcept;

/// (H6) Four-edge orifice flows of the spool valve (Hopsan Hydraulic43Valve edges with laps):
/// Q_edge = K_v * open(x - lap) / x_max * ssqrt(dp), K_v = Q_rated / sqrt(dp_rated).
/// Flows into the chambers: Q_a = Q_pa - Q_at, Q_b = Q_pb - Q_bt, and their partial derivatives.
struct ValveFlows {
  double q_a_m3ps = 0.0;
  double q_b_m3ps = 0.0;
  double dqa_dx = 0.0;  ///< per unit of normalised spool position
  double dqb_dx = 0.0;
  double dqa_dpa = 0.0;  ///< [m^3/s/Pa]
  double dqb_dpb = 0.0;
};
/// @param x_spool normalised spool position (clamped to [-1, 1])
/// @rt
[[nodiscard]] ValveFlows valveFlows(const JointParams& p, double x_spool, double p_a_pa, double p_b_pa) noexcept;

/// (H11) Check-valve flow into a chamber at pressure p: G [ramp(p_r - p) - ramp(p - p_s)]
/// (rounded ramps of width linear_region_pa / 10), and its slope d/dp.
/// @rt
[[nodiscard]] ValueSlope checkValveFlow(const JointParams& p, double p_pa) noexcept;

/// (H7) Friction torque [N m]: [tau_c + (tau_s - tau_c) exp(-(w/w_s)^2)] tanh(w/eps) + b w, and d/dw.
/// @rt
[[nodiscard]] ValueSlope frictionTorque(const FrictionParams& f, double qd_radps) noexcept;

/// (H8) Hard-stop torque [N m] (Hunt-Crossley penalty) and its partials.
struct StopTorque {
  double torque_nm = 0.0;
  double d_dq = 0.0;
  double d_dqd = 0.0;
};
/// @rt
[[nodiscard]] StopTorque hardStopTorque(const JointParams& p, double q_rad, double qd_radps) noexcept;

/// Linearised figures of merit (Merritt, Hydraulic Control Systems, ch. 2 and 6;
/// docs/sources.md, Plant 1.6), for a vane or a cylinder (D = A R(q)) with equal areas.
/// (H9) hydraulic stiffness K_h = beta D^2 (1/V_a + 1/V_b) [N m/rad] at q, pressures p [Pa].
/// @rt
[[nodiscard]] double hydraulicStiffness(const JointParams& p, double q_rad, double pressure_pa) noexcept;

/// (H10) ideal no-load flow gain K_q = dQ_L/dx at x = 0 with both edges of a path open
/// and load pressure 0: Q_L = K_v x sqrt((p_s - p_r)/2) [m^3/s per unit opening].
/// @rt
[[nodiscard]] double noLoadFlowGain(const JointParams& p) noexcept;

/// Valve coefficient K_v = rated flow / sqrt(rated drop) [m^3/s/sqrt(Pa)].
/// @rt
[[nodiscard]] double valveCoefficient(const ValveParams& v) noexcept;

}  // namespace fullarm::plant
