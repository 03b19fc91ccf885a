#include "fullarm/plant/joint_params.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

#include "fullarm/core/config_error.hpp"

namespace fullarm::plant {
namespace {

class Checker {
 public:
  Checker(const std::string& file, const std::string& prefix) : file_(file), prefix_(prefix) {}

  [[noreturn]] void fail(const std::string& key, double value, const std::string& expected) const {
    std::ostringstream s;
    s.precision(12);
    s << "value " << value << " is invalid: expected " << expected;
    throw core::ConfigError(file_, prefix_.empty() ? key : prefix_ + "." + key, s.str());
  }
  void positive(const std::string& key, double v) const {
    if (!(std::isfinite(v) && v > 0.0)) fail(key, v, "a finite number > 0");
  }
  void nonNegative(const std::string& key, double v) const {
    if (!(std::isfinite(v) && v >= 0.0)) fail(key, v, "a finite number >= 0");
  }
  void range(const std::string& key, double v, double lo, double hi) const {
    if (!(std::isfinite(v) && v >= lo && v <= hi)) {
      std::ostringstream s;
      s << "a number in [" << lo << ", " << hi << "]";
      fail(key, v, s.str());
    }
  }

 private:
  const std::string& file_;
  const std::string& prefix_;
};

}  // namespace

void validateJointParams(const JointParams& p, const std::string& file, const std::string& key_path) {
  const Checker c(file, key_path);
  if (!(p.max_rad > p.min_rad)) c.fail("limits.max_rad", p.max_rad, "a joint range with max_rad > min_rad");
  if (p.actuator.kind == ActuatorKind::kIdealTorque) {
    c.nonNegative("actuator.inertia_kgm2", p.actuator.inertia_kgm2);
    return;
  }
  c.positive("supply_pressure_pa", p.supply_pressure_pa);
  c.nonNegative("return_pressure_pa", p.return_pressure_pa);
  if (!(p.supply_pressure_pa > p.return_pressure_pa)) {
    c.fail("supply_pressure_pa", p.supply_pressure_pa, "a supply pressure above the return pressure");
  }
  const ValveParams& v = p.valve;
  c.range("valve.natural_frequency_hz", v.natural_frequency_hz, 1.0, 5000.0);
  c.range("valve.damping_ratio", v.damping_ratio, 0.05, 5.0);
  c.positive("valve.amplifier_gain_per_v", v.amplifier_gain_per_v);
  c.positive("valve.spool_stroke_m", v.spool_stroke_m);
  c.positive("valve.rated_flow_m3ps", v.rated_flow_m3ps);
  c.positive("valve.rated_pressure_drop_pa", v.rated_pressure_drop_pa);
  for (const auto& [key, lap] : {std::pair{"valve.lap_pa_m", v.lap_pa_m}, std::pair{"valve.lap_pb_m", v.lap_pb_m},
                                 std::pair{"valve.lap_at_m", v.lap_at_m}, std::pair{"valve.lap_bt_m", v.lap_bt_m}}) {
    c.range(key, lap, -0.5 * v.spool_stroke_m, 0.5 * v.spool_stroke_m);
  }
  c.range("valve.edge_rounding_m", v.edge_rounding_m, 1e-12, 0.1 * v.spool_stroke_m);
  c.range("valve.linear_region_pa", v.linear_region_pa, 1.0, 0.1 * p.supply_pressure_pa);
  const FluidParams& f = p.fluid;
  c.range("fluid.oil_bulk_modulus_pa", f.oil_bulk_modulus_pa, 1e7, 1e11);
  c.range("fluid.air_fraction", f.air_fraction, 0.0, 0.2);
  c.range("fluid.polytropic_index", f.polytropic_index, 1.0, 1.67);
  c.positive("fluid.atmospheric_pressure_pa", f.atmospheric_pressure_pa);
  c.positive("chambers.dead_volume_a_m3", p.chambers.dead_volume_a_m3);
  c.positive("chambers.dead_volume_b_m3", p.chambers.dead_volume_b_m3);
  c.nonNegative("chambers.internal_leakage_m3ps_per_pa", p.chambers.internal_leakage_m3ps_per_pa);
  c.nonNegative("chambers.external_leakage_m3ps_per_pa", p.chambers.external_leakage_m3ps_per_pa);
  c.nonNegative("chambers.check_valve_conductance_m3ps_per_pa", p.chambers.check_valve_conductance_m3ps_per_pa);
  const ActuatorParams& a = p.actuator;
  c.nonNegative("actuator.inertia_kgm2", a.inertia_kgm2);
  if (a.kind == ActuatorKind::kRotaryVane) {
    c.positive("actuator.displacement_m3_per_rad", a.displacement_m3_per_rad);
  } else {
    c.positive("actuator.piston_area_a_m2", a.piston_area_a_m2);
    c.positive("actuator.piston_area_b_m2", a.piston_area_b_m2);
    c.positive("actuator.lever.moment_arm_m", a.lever.moment_arm_m);
    if (!(a.lever.mount_distance_m > a.lever.moment_arm_m)) {
      c.fail("actuator.lever.mount_distance_m", a.lever.mount_distance_m,
             "a mount distance larger than the moment arm");
    }
    // The moment arm must keep one sign over the joint range (lever never passes the mount line).
    const double phi0 = p.min_rad + a.lever.lever_angle_offset_rad;
    const double phi1 = p.max_rad + a.lever.lever_angle_offset_rad;
    const double k0 = std::floor(phi0 / std::numbers::pi);
    if (std::floor(phi1 / std::numbers::pi) != k0 || std::abs(std::sin(phi0)) < 1e-3 ||
        std::abs(std::sin(phi1)) < 1e-3) {
      c.fail("actuator.lever.lever_angle_offset_rad", a.lever.lever_angle_offset_rad,
             "a lever whose angle q + offset stays strictly inside (0, pi) or (-pi, 0) over the joint range");
    }
  }
  const FrictionParams& fr = p.friction;
  c.nonNegative("friction.coulomb_nm", fr.coulomb_nm);
  if (!(fr.static_nm >= fr.coulomb_nm)) c.fail("friction.static_nm", fr.static_nm, "static friction >= coulomb_nm");
  c.positive("friction.stribeck_velocity_radps", fr.stribeck_velocity_radps);
  c.nonNegative("friction.viscous_nms_per_rad", fr.viscous_nms_per_rad);
  c.positive("friction.smoothing_velocity_radps", fr.smoothing_velocity_radps);
  c.positive("hard_stop.stiffness_nm_per_rad", p.hard_stop.stiffness_nm_per_rad);
  c.nonNegative("hard_stop.damping_s_per_rad", p.hard_stop.damping_s_per_rad);
  c.positive("torque_loop.gain_v_per_nm", p.torque_loop.gain_v_per_nm);
  c.nonNegative("sensors.angle_noise_rad", p.sensor_noise.angle_noise_rad);
  c.nonNegative("sensors.torque_noise_nm", p.sensor_noise.torque_noise_nm);
  if (!std::isfinite(p.sensor_noise.torque_bias_nm))
    c.fail("sensors.torque_bias_nm", p.sensor_noise.torque_bias_nm, "a finite number");
  c.nonNegative("sensors.torque_filter_hz", p.sensor_noise.torque_filter_hz);
  const double full_scale = p.sensor_noise.pressure_full_scale_pa;
  if (!(full_scale == 0.0 || (std::isfinite(full_scale) && full_scale >= p.supply_pressure_pa))) {
    c.fail("sensors.pressure_full_scale_pa", full_scale,
           "0 (no pressure transducers) or a full scale of at least the supply pressure");
  }
  c.range("sensors.pressure_bits", p.sensor_noise.pressure_bits, 8, 24);
  c.nonNegative("sensors.pressure_noise_pa", p.sensor_noise.pressure_noise_pa);
  if (p.potentiometer.slope_rad_per_count == 0.0 || p.torque_sensor.slope_nm_per_count == 0.0) {
    c.fail("sensors", 0.0, "non-zero potentiometer and torque-sensor slopes (from the arm model)");
  }
}

}  // namespace fullarm::plant
