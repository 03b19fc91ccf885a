#include "fullarm/identification/joint_groups.hpp"

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
  m.value[kLoadTorque] = load_torque_nm;
  m.delay_samples = delay_samples;
  return m;
}

}  // namespace fullarm::identification
