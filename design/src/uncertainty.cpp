#include "fullarm/design/uncertainty.hpp"

#include "fullarm/core/random.hpp"
#include "fullarm/design/scenario_analysis.hpp"

namespace fullarm::design {

// V2: counter-based random streams (reports/equations.md).
ModelVariation drawVariation(const UncertaintyRanges& r, std::uint64_t seed, int joint_slot, int index) noexcept {
  core::RandomStream stream(seed, static_cast<std::uint64_t>(joint_slot), static_cast<std::uint64_t>(index));
  ModelVariation s;
  s.index = index;
  s.bulk_modulus_scale = stream.uniform(r.bulk_modulus_scale.min, r.bulk_modulus_scale.max);
  s.valve_gain_scale = stream.uniform(r.valve_gain_scale.min, r.valve_gain_scale.max);
  s.friction_scale = stream.uniform(r.friction_scale.min, r.friction_scale.max);
  s.inertia_scale = stream.uniform(r.inertia_scale.min, r.inertia_scale.max);
  s.user_stiffness_nm_per_rad = stream.uniform(r.user_stiffness_nm_per_rad.min, r.user_stiffness_nm_per_rad.max);
  s.user_damping_nms_per_rad = stream.uniform(r.user_damping_nms_per_rad.min, r.user_damping_nms_per_rad.max);
  s.delay_samples = stream.uniformInt(r.delay_min_samples, r.delay_max_samples);
  return s;
}

JointPlantModel applyVariation(const JointPlantModel& nominal, const ModelVariation& v) {
  JointPlantModel m = nominal;
  m.joint.fluid.oil_bulk_modulus_pa *= v.bulk_modulus_scale;
  m.joint.valve.rated_flow_m3ps *= v.valve_gain_scale;
  m.load.inertia_kgm2 *= v.inertia_scale;
  m.load.user_inertia_kgm2 *= v.inertia_scale;
  m.joint.friction.viscous_nms_per_rad *= v.friction_scale;
  m.joint.friction.coulomb_nm *= v.friction_scale;
  m.joint.friction.static_nm *= v.friction_scale;
  m.load.user_stiffness_nm_per_rad = v.user_stiffness_nm_per_rad;
  m.load.user_damping_nms_per_rad = v.user_damping_nms_per_rad;
  return m;
}

JointScenario variationScenario(const JointScenario& nominal, const ModelVariation& v) {
  const JointPlantModel m = applyVariation(scenarioPlantModel(nominal), v);
  JointScenario sc = nominal;
  sc.joint = m.joint;
  sc.load.inertia_kgm2 = m.load.inertia_kgm2 + m.load.user_inertia_kgm2;
  sc.user.inertia_kgm2 = m.load.user_inertia_kgm2;
  sc.user.stiffness_nm_per_rad = m.load.user_stiffness_nm_per_rad;
  sc.user.damping_nms_per_rad = m.load.user_damping_nms_per_rad;
  sc.delay_samples = v.delay_samples;
  // Each run its own sensor-noise stream.
  sc.noise_seed = nominal.noise_seed + 1000003ULL * static_cast<std::uint64_t>(v.index + 1);
  return sc;
}

PreparedJoint prepareVariation(const JointPlantModel& nominal, double q_rad, const LoopSetup& setup,
                               const ModelVariation& v) {
  const JointPlantModel m = applyVariation(nominal, v);
  LoopSetup s = setup;
  s.delay_samples = v.delay_samples;
  return prepareJoint(m, solveOperatingPoint(m, q_rad), s);
}

}  // namespace fullarm::design
