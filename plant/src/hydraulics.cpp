#include "fullarm/plant/hydraulics.hpp"

#include <algorithm>
#include <cmath>

#include "fullarm/arm/actuator.hpp"

namespace fullarm::plant {

namespace {

// The bodies of regularizedSignedSqrt and roundedRamp, always inlined into the valve and check-valve
// flows (eight ramps and four roots per joint and right-hand side; as calls they cost more than their
// arithmetic).
[[gnu::always_inline]] inline ValueSlope signedSqrtInline(double x, double x0) noexcept {
  const double ax = std::abs(x);
  if (ax >= x0) {
    const double r = std::sqrt(ax);
    return {x >= 0.0 ? r : -r, 0.5 / r};
  }
  // (H1) odd cubic a x + b x^3 with a = 5/(4 sqrt(x0)), b = -1/(4 x0^2 sqrt(x0)): value and
  // slope equal sign(x) sqrt(|x|) and 1/(2 sqrt(|x|)) at |x| = x0.
  const double inv_sqrt = 1.0 / std::sqrt(x0);
  const double u = x / x0;
  return {inv_sqrt * x * (1.25 - 0.25 * u * u), inv_sqrt * (1.25 - 0.75 * u * u)};
}

[[gnu::always_inline]] inline ValueSlope roundedRampInline(double s, double w) noexcept {
  if (s <= -w) return {0.0, 0.0};
  if (s >= w) return {s, 1.0};
  // (H2) quadratic blend with matching value and slope at +-w.
  return {(s + w) * (s + w) / (4.0 * w), (s + w) / (2.0 * w)};
}

}  // namespace

// H1: C1 signed square root (reports/equations.md).
ValueSlope regularizedSignedSqrt(double x, double x0) noexcept {
  return signedSqrtInline(x, x0);
}

// H2: C1 rounded edge opening (reports/equations.md).
ValueSlope roundedRamp(double s, double w) noexcept {
  return roundedRampInline(s, w);
}

double airRoot(const FluidParams& f) noexcept {
  return std::pow(f.atmospheric_pressure_pa, 1.0 / f.polytropic_index);
}

ValueSlope effectiveBulkModulus(const FluidParams& f, double p_gauge_pa) noexcept {
  return effectiveBulkModulus(f, p_gauge_pa, airRoot(f));
}

ValueSlope effectiveBulkModulus(const FluidParams& f, double p_gauge_pa, double air_root) noexcept {
  const double el = f.oil_bulk_modulus_pa;
  if (f.air_fraction <= 0.0) return {el, 0.0};
  const double pa = f.atmospheric_pressure_pa;
  const double n = f.polytropic_index;
  const double a = f.air_fraction;
  // (H3) with x = p_abs^(1/n), c = p_atm^(1/n): E = E_l (1 + a c / x) / (1 + a c E_l / (n p_abs x)).
  const bool clamped = pa + p_gauge_pa < 0.1 * pa;
  const double pabs = clamped ? 0.1 * pa : pa + p_gauge_pa;
  const double x = std::exp(std::log(pabs) / n);  // p_abs^(1/n)
  const double c = air_root;
  const double num = 1.0 + a * c / x;
  const double den = 1.0 + a * c * el / (n * pabs * x);
  const double dnum = clamped ? 0.0 : -a * c / (n * pabs * x);
  const double dden = clamped ? 0.0 : -a * c * el * (1.0 + 1.0 / n) / (n * pabs * pabs * x);
  return {el * num / den, el * (dnum * den - num * dden) / (den * den)};
}

namespace {

// (H4) from cos phi and sin phi.
ActuatorKinematics cylinderKinematics(const ActuatorParams& a, double c, double s) noexcept {
  const double r = a.lever.moment_arm_m;
  const double d = a.lever.mount_distance_m;
  // L and R as arm::cylinderLength / arm::actuatorMomentArm (law of cosines and dL/dq).
  const double L = std::sqrt(r * r + d * d - 2.0 * r * d * c);
  const double R = r * d * s / L;
  // dR/dq = r d cos(phi) / L - R^2 / L (differentiating R = r d sin(phi) / L, dL/dq = R).
  const double dR = (r * d * c - R * R) / L;
  return {L, R, dR};
}

}  // namespace

// H4: cylinder on lever kinematics (reports/equations.md).
ActuatorKinematics actuatorKinematics(const ActuatorParams& a, double q_rad) noexcept {
  if (a.kind != ActuatorKind::kCylinder) return {q_rad, 1.0, 0.0};
  const double phi = q_rad + a.lever.lever_angle_offset_rad;
  return cylinderKinematics(a, std::cos(phi), std::sin(phi));
}

SinCos leverOffsetSinCos(const ActuatorParams& a) noexcept {
  if (a.kind != ActuatorKind::kCylinder) return {};
  return {std::sin(a.lever.lever_angle_offset_rad), std::cos(a.lever.lever_angle_offset_rad)};
}

ActuatorKinematics actuatorKinematics(const ActuatorParams& a, double q_rad, SinCos q, SinCos lever_offset) noexcept {
  if (a.kind != ActuatorKind::kCylinder) return {q_rad, 1.0, 0.0};
  // phi = q + offset by angle addition.
  return cylinderKinematics(a, q.cos * lever_offset.cos - q.sin * lever_offset.sin,
                            q.sin * lever_offset.cos + q.cos * lever_offset.sin);
}

double areaA(const ActuatorParams& a) noexcept {
  return a.kind == ActuatorKind::kCylinder ? a.piston_area_a_m2 : a.displacement_m3_per_rad;
}

double areaB(const ActuatorParams& a) noexcept {
  return a.kind == ActuatorKind::kCylinder ? a.piston_area_b_m2 : a.displacement_m3_per_rad;
}

StrokeRange strokeRange(const JointParams& p) noexcept {
  const double s0 = actuatorKinematics(p.actuator, p.min_rad).stroke;
  const double s1 = actuatorKinematics(p.actuator, p.max_rad).stroke;
  return {std::min(s0, s1), std::max(s0, s1), s1 >= s0};
}

namespace {

// (H5) from the actuator kinematics at q.
ChamberVolumes volumesFrom(const JointParams& p, const StrokeRange& range, const ActuatorKinematics& k) noexcept {
  // u = sign * s increases with q, so chamber A (filling as u grows) drives q positive.
  const double sign = range.increasing ? 1.0 : -1.0;
  const double u = sign * k.stroke;
  const double u_min = range.increasing ? range.s_min : -range.s_max;
  const double u_max = range.increasing ? range.s_max : -range.s_min;
  const double aa = areaA(p.actuator);
  const double ab = areaB(p.actuator);
  ChamberVolumes v;
  // (H5)
  v.v_a_m3 = p.chambers.dead_volume_a_m3 + aa * (u - u_min);
  v.v_b_m3 = p.chambers.dead_volume_b_m3 + ab * (u_max - u);
  v.dva_dq = aa * sign * k.ratio;
  v.dvb_dq = -ab * sign * k.ratio;
  v.d2va_dq2 = aa * sign * k.ratio_slope;
  v.d2vb_dq2 = -ab * sign * k.ratio_slope;
  return v;
}

}  // namespace

// H5: chamber volumes (reports/equations.md).
ChamberVolumes chamberVolumes(const JointParams& p, const StrokeRange& range, double q_rad) noexcept {
  return volumesFrom(p, range, actuatorKinematics(p.actuator, q_rad));
}

ChamberVolumes chamberVolumes(const JointParams& p, const StrokeRange& range, double q_rad, SinCos q,
                              SinCos lever_offset) noexcept {
  return volumesFrom(p, range, actuatorKinematics(p.actuator, q_rad, q, lever_offset));
}

double valveCoefficient(const ValveParams& v) noexcept {
  return v.rated_flow_m3ps / std::sqrt(v.rated_pressure_drop_pa);
}

ValveFlows valveFlows(const JointParams& p, double x_spool, double p_a_pa, double p_b_pa) noexcept {
  const ValveParams& v = p.valve;
  const double kv = valveCoefficient(v);
  const double stroke = v.spool_stroke_m;
  const double x = std::clamp(x_spool, -1.0, 1.0) * stroke;
  const double dx_dxn = (x_spool > -1.0 && x_spool < 1.0) ? stroke : 0.0;
  const double w = v.edge_rounding_m;
  // (H6) edge openings [m] (Hopsan Hydraulic43Valve with per-edge laps; rounded, H2).
  const ValueSlope o_pa = roundedRampInline(x - v.lap_pa_m, w);
  const ValueSlope o_pb = roundedRampInline(-x - v.lap_pb_m, w);
  const ValueSlope o_at = roundedRampInline(-x - v.lap_at_m, w);
  const ValueSlope o_bt = roundedRampInline(x - v.lap_bt_m, w);
  const double ps = p.supply_pressure_pa;
  const double pr = p.return_pressure_pa;
  const double x0 = v.linear_region_pa;
  const ValueSlope r_pa = signedSqrtInline(ps - p_a_pa, x0);
  const ValueSlope r_at = signedSqrtInline(p_a_pa - pr, x0);
  const ValueSlope r_pb = signedSqrtInline(ps - p_b_pa, x0);
  const ValueSlope r_bt = signedSqrtInline(p_b_pa - pr, x0);
  const double g = kv / stroke;  // flow per metre of opening per sqrt(Pa)
  ValveFlows f;
  f.q_a_m3ps = g * (o_pa.value * r_pa.value - o_at.value * r_at.value);
  f.q_b_m3ps = g * (o_pb.value * r_pb.value - o_bt.value * r_bt.value);
  f.dqa_dx = g * (o_pa.slope * r_pa.value + o_at.slope * r_at.value) * dx_dxn;
  f.dqb_dx = g * (-o_pb.slope * r_pb.value - o_bt.slope * r_bt.value) * dx_dxn;
  f.dqa_dpa = g * (-o_pa.value * r_pa.slope - o_at.value * r_at.slope);
  f.dqb_dpb = g * (-o_pb.value * r_pb.slope - o_bt.value * r_bt.slope);
  return f;
}

ValueSlope checkValveFlow(const JointParams& p, double p_pa) noexcept {
  const double g = p.chambers.check_valve_conductance_m3ps_per_pa;
  if (g <= 0.0) return {0.0, 0.0};
  const double w = 0.1 * p.valve.linear_region_pa;
  // (H11) anti-cavitation (from return) and relief (to supply) check valves, no cracking pressure.
  const ValueSlope in = roundedRampInline(p.return_pressure_pa - p_pa, w);
  const ValueSlope out = roundedRampInline(p_pa - p.supply_pressure_pa, w);
  return {g * (in.value - out.value), g * (-in.slope - out.slope)};
}

ValueSlope frictionTorque(const FrictionParams& f, double w) noexcept {
  // (H7) Coulomb + Stribeck + viscous, tanh-smoothed sign.
  const double e = std::exp(-(w / f.stribeck_velocity_radps) * (w / f.stribeck_velocity_radps));
  const double level = f.coulomb_nm + (f.static_nm - f.coulomb_nm) * e;
  const double dlevel =
      (f.static_nm - f.coulomb_nm) * e * (-2.0 * w / (f.stribeck_velocity_radps * f.stribeck_velocity_radps));
  const double th = std::tanh(w / f.smoothing_velocity_radps);
  const double dth = (1.0 - th * th) / f.smoothing_velocity_radps;
  return {level * th + f.viscous_nms_per_rad * w, dlevel * th + level * dth + f.viscous_nms_per_rad};
}

StopTorque hardStopTorque(const JointParams& p, double q, double qd) noexcept {
  const double k = p.hard_stop.stiffness_nm_per_rad;
  const double c = p.hard_stop.damping_s_per_rad;
  StopTorque s;
  // (H8) Hunt-Crossley: tau = -K pen (1 + c pen_rate), smooth inside contact (no clamp, so the
  // only non-smooth points are contact and release, which CVODES locates by root finding).
  if (q > p.max_rad) {
    const double pen = q - p.max_rad;
    s = {-k * pen * (1.0 + c * qd), -k * (1.0 + c * qd), -k * pen * c};
  } else if (q < p.min_rad) {
    const double pen = p.min_rad - q;
    s = {k * pen * (1.0 - c * qd), -k * (1.0 - c * qd), -k * pen * c};
  }
  return s;
}

double hydraulicStiffness(const JointParams& p, double q_rad, double pressure_pa) noexcept {
  const ChamberVolumes v = chamberVolumes(p, strokeRange(p), q_rad);
  const double beta = effectiveBulkModulus(p.fluid, pressure_pa).value;
  const double ratio = actuatorKinematics(p.actuator, q_rad).ratio;
  const double da = areaA(p.actuator) * ratio;
  const double db = areaB(p.actuator) * ratio;
  // (H9) Merritt: K_h = beta (D_a^2 / V_a + D_b^2 / V_b).
  return beta * (da * da / v.v_a_m3 + db * db / v.v_b_m3);
}

double noLoadFlowGain(const JointParams& p) noexcept {
  // (H10) with p_a = p_b = (p_s + p_r)/2 each open edge sees (p_s - p_r)/2.
  return valveCoefficient(p.valve) * std::sqrt(0.5 * (p.supply_pressure_pa - p.return_pressure_pa));
}

}  // namespace fullarm::plant
