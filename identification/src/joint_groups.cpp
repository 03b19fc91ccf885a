#include "fullarm/identification/joint_groups.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

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
  const double lap_m =
      0.25 * (joint.valve.lap_pa_m + joint.valve.lap_pb_m + joint.valve.lap_at_m + joint.valve.lap_bt_m);
  m.underlap_v = std::max(0.0, -lap_m) / metre_per_volt;
  m.edge_rounding_v = joint.valve.edge_rounding_m / metre_per_volt;
  m.spool_hz = joint.valve.natural_frequency_hz;
  m.spool_damping = joint.valve.damping_ratio;
  m.torque_filter_hz = joint.sensor_noise.torque_filter_hz;
  m.value[kLoadTorque] = load_torque_nm;
  m.delay_samples = delay_samples;
  return m;
}

// (I12) tau_hyd = p_a dV_a/dq + p_b dV_b/dq through the plant's chamber geometry (H5).
std::vector<double> hydraulicTorque(const plant::JointParams& joint, const std::vector<double>& q_rad,
                                    const std::vector<double>& p_a_pa, const std::vector<double>& p_b_pa) {
  if (q_rad.size() != p_a_pa.size() || q_rad.size() != p_b_pa.size()) {
    throw std::invalid_argument("hydraulic torque: " + std::to_string(q_rad.size()) + " angles, " +
                                std::to_string(p_a_pa.size()) + " and " + std::to_string(p_b_pa.size()) +
                                " chamber pressures");
  }
  if (joint.actuator.kind == plant::ActuatorKind::kIdealTorque) {
    throw std::invalid_argument("hydraulic torque: joint " + joint.name + " has no hydraulic actuator");
  }
  const plant::StrokeRange range = plant::strokeRange(joint);
  std::vector<double> tau(q_rad.size());
  for (std::size_t k = 0; k < q_rad.size(); ++k) {
    const plant::ChamberVolumes v = plant::chamberVolumes(joint, range, q_rad[k]);
    tau[k] = p_a_pa[k] * v.dva_dq + p_b_pa[k] * v.dvb_dq;
  }
  return tau;
}

void addHydraulicTorque(ExperimentData& data, const SignalTable& log, const plant::JointParams& joint) {
  const bool a = log.has(kPressureColumns[0]);
  const bool b = log.has(kPressureColumns[1]);
  if (!a && !b) return;
  if (!(a && b)) {
    const std::string& present = a ? kPressureColumns[0] : kPressureColumns[1];
    const std::string& missing = a ? kPressureColumns[1] : kPressureColumns[0];
    throw std::invalid_argument("experiment log: column " + present + " but no column " + missing +
                                ": the chamber pressures come as a pair");
  }
  if (log.rows() != data.q_rad.size()) {
    throw std::invalid_argument("experiment log: " + std::to_string(log.rows()) + " rows, the experiment " +
                                std::to_string(data.q_rad.size()));
  }
  data.tau_hydraulic_nm =
      hydraulicTorque(joint, data.q_rad, log.column(kPressureColumns[0]), log.column(kPressureColumns[1]));
}

}  // namespace fullarm::identification
