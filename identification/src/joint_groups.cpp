#include "fullarm/identification/joint_groups.hpp"

#include <algorithm>
#include <cmath>

#include "fullarm/plant/hydraulics.hpp"

namespace fullarm::identification {

GreyModel greyModelFromJoint(const plant::JointParams& joint, double q_rad, double link_inertia_kgm2,
                             double load_torque_nm, int delay_samples) {
  const plant::ActuatorKinematics kin = plant::actuatorKinematics(joint.actuator, q_rad);
  const double d = plant::areaA(joint.actuator) * std::abs(kin.ratio);
  GreyModel m;
  m.value[kFlowGain] = joint.valve.amplifier_gain_per_v * plant::noLoadFlowGain(joint) / d;
  m.value[kStiffness] =
      plant::hydraulicStiffness(joint, q_rad, 0.5 * (joint.supply_pressure_pa + joint.return_pressure_pa));
  m.value[kLeakage] = joint.chambers.internal_leakage_m3ps_per_pa / (d * d);
  m.value[kInertia] = link_inertia_kgm2 + joint.actuator.inertia_kgm2;
  m.value[kViscous] = joint.friction.viscous_nms_per_rad;
  m.value[kCoulomb] = joint.friction.coulomb_nm;
  m.value[kStribeck] = std::max(0.0, joint.friction.static_nm - joint.friction.coulomb_nm);
  m.coulomb_smoothing_radps = joint.friction.smoothing_velocity_radps;
  m.stribeck_velocity_radps = joint.friction.stribeck_velocity_radps;
  // The valve's structure: the stall torque of the orifice law, the metering edges' underlap and
  // rounding in volts of command (a lap below zero is an underlap).
  m.stall_torque_nm = d * (joint.supply_pressure_pa - joint.return_pressure_pa);
  const double metre_per_volt = joint.valve.spool_stroke_m * joint.valve.amplifier_gain_per_v;
  const double lap_m = 0.25 * (joint.valve.lap_pa_m + joint.valve.lap_pb_m + joint.valve.lap_at_m + joint.valve.lap_bt_m);
  m.underlap_v = std::max(0.0, -lap_m) / metre_per_volt;
  m.edge_rounding_v = joint.valve.edge_rounding_m / metre_per_volt;
  m.spool_hz = joint.valve.natural_frequency_hz;
  m.spool_damping = joint.valve.damping_ratio;
  m.torque_filter_hz = joint.sensor_noise.torque_filter_hz;
  m.value[kLoadTorque] = load_torque_nm;
  m.delay_samples = delay_samples;
  return m;
}

}  // namespace fullarm::identification
