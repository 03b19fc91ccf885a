// formatPlantConfigYaml against the loader: the shipped plant written and read back gives the same
// doubles in every field the schema holds; a plant with two fluids is refused.

#include <gtest/gtest.h>

#include <stdexcept>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::plant {
namespace {

TEST(PlantConfigYamlTest, WrittenPlantReadsBackToTheSameDoubles) {
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  PlantConfig a = loadPlantConfig(defaultPlantConfigPath(), model);
  // Values that do not print short, and non-default choices, so that every digit and key matters.
  a.joints[2].valve.rated_flow_m3ps = 6.1234567890123457e-6;
  a.joints[3].chambers.dead_volume_a_m3 = 1.0 / 3.0 * 1e-6;
  a.joints[4].friction.static_nm = 0.7 + 1e-15;
  a.solver.integrator = IntegratorKind::kRodas4;
  a.solver.jacobian = JacobianKind::kFiniteDifference;
  a.user_arm.enabled = true;
  a.user_arm.point_L = {0.1, -0.2, 1.0 / 7.0};
  a.seed = 42;
  a.joints[3].sensor_noise.pressure_full_scale_pa = 25.0e6 + 1.0 / 3.0;
  a.joints[3].sensor_noise.pressure_bits = 14;
  a.joints[3].sensor_noise.pressure_noise_pa = 1.0e4 / 3.0;
  const PlantConfig b = parsePlantConfig(formatPlantConfigYaml(a, model, {"a header line"}), "written.yaml", model);
  EXPECT_EQ(b.seed, a.seed);
  EXPECT_EQ(b.solver.integrator, a.solver.integrator);
  EXPECT_EQ(b.solver.jacobian, a.solver.jacobian);
  EXPECT_EQ(b.solver.rtol, a.solver.rtol);
  EXPECT_EQ(b.solver.atol_pressure_pa, a.solver.atol_pressure_pa);
  EXPECT_EQ(b.solver.max_steps_per_period, a.solver.max_steps_per_period);
  EXPECT_EQ(b.solver.reinit_command_jump, a.solver.reinit_command_jump);
  EXPECT_EQ(b.user_arm.enabled, a.user_arm.enabled);
  EXPECT_EQ(b.user_arm.link, a.user_arm.link);
  EXPECT_EQ(b.user_arm.point_L, a.user_arm.point_L);
  EXPECT_EQ(b.user_arm.mass_kg, a.user_arm.mass_kg);
  EXPECT_EQ(b.user_arm.stiffness_n_per_m, a.user_arm.stiffness_n_per_m);
  EXPECT_EQ(b.user_arm.damping_ns_per_m, a.user_arm.damping_ns_per_m);
  ASSERT_EQ(b.joints.size(), a.joints.size());
  for (std::size_t k = 0; k < a.joints.size(); ++k) {
    const JointParams& x = a.joints[k];
    const JointParams& y = b.joints[k];
    SCOPED_TRACE(x.name);
    EXPECT_EQ(y.name, x.name);
    EXPECT_EQ(y.input_mode, x.input_mode);
    EXPECT_EQ(y.supply_pressure_pa, x.supply_pressure_pa);
    EXPECT_EQ(y.return_pressure_pa, x.return_pressure_pa);
    EXPECT_EQ(y.fluid.oil_bulk_modulus_pa, x.fluid.oil_bulk_modulus_pa);
    EXPECT_EQ(y.fluid.air_fraction, x.fluid.air_fraction);
    EXPECT_EQ(y.fluid.polytropic_index, x.fluid.polytropic_index);
    EXPECT_EQ(y.fluid.atmospheric_pressure_pa, x.fluid.atmospheric_pressure_pa);
    const ValveParams &v = x.valve, &w = y.valve;
    EXPECT_EQ(w.natural_frequency_hz, v.natural_frequency_hz);
    EXPECT_EQ(w.damping_ratio, v.damping_ratio);
    EXPECT_EQ(w.amplifier_gain_per_v, v.amplifier_gain_per_v);
    EXPECT_EQ(w.spool_stroke_m, v.spool_stroke_m);
    EXPECT_EQ(w.rated_flow_m3ps, v.rated_flow_m3ps);
    EXPECT_EQ(w.rated_pressure_drop_pa, v.rated_pressure_drop_pa);
    EXPECT_EQ(w.lap_pa_m, v.lap_pa_m);
    EXPECT_EQ(w.lap_pb_m, v.lap_pb_m);
    EXPECT_EQ(w.lap_at_m, v.lap_at_m);
    EXPECT_EQ(w.lap_bt_m, v.lap_bt_m);
    EXPECT_EQ(w.edge_rounding_m, v.edge_rounding_m);
    EXPECT_EQ(w.linear_region_pa, v.linear_region_pa);
    EXPECT_EQ(y.actuator.kind, x.actuator.kind);
    EXPECT_EQ(y.actuator.displacement_m3_per_rad, x.actuator.displacement_m3_per_rad);
    EXPECT_EQ(y.actuator.piston_area_a_m2, x.actuator.piston_area_a_m2);
    EXPECT_EQ(y.actuator.piston_area_b_m2, x.actuator.piston_area_b_m2);
    EXPECT_EQ(y.actuator.inertia_kgm2, x.actuator.inertia_kgm2);
    EXPECT_EQ(y.chambers.dead_volume_a_m3, x.chambers.dead_volume_a_m3);
    EXPECT_EQ(y.chambers.dead_volume_b_m3, x.chambers.dead_volume_b_m3);
    EXPECT_EQ(y.chambers.internal_leakage_m3ps_per_pa, x.chambers.internal_leakage_m3ps_per_pa);
    EXPECT_EQ(y.chambers.external_leakage_m3ps_per_pa, x.chambers.external_leakage_m3ps_per_pa);
    EXPECT_EQ(y.chambers.check_valve_conductance_m3ps_per_pa, x.chambers.check_valve_conductance_m3ps_per_pa);
    EXPECT_EQ(y.friction.coulomb_nm, x.friction.coulomb_nm);
    EXPECT_EQ(y.friction.static_nm, x.friction.static_nm);
    EXPECT_EQ(y.friction.stribeck_velocity_radps, x.friction.stribeck_velocity_radps);
    EXPECT_EQ(y.friction.viscous_nms_per_rad, x.friction.viscous_nms_per_rad);
    EXPECT_EQ(y.friction.smoothing_velocity_radps, x.friction.smoothing_velocity_radps);
    EXPECT_EQ(y.hard_stop.stiffness_nm_per_rad, x.hard_stop.stiffness_nm_per_rad);
    EXPECT_EQ(y.hard_stop.damping_s_per_rad, x.hard_stop.damping_s_per_rad);
    EXPECT_EQ(y.torque_loop.gain_v_per_nm, x.torque_loop.gain_v_per_nm);
    EXPECT_EQ(y.sensor_noise.angle_noise_rad, x.sensor_noise.angle_noise_rad);
    EXPECT_EQ(y.sensor_noise.torque_noise_nm, x.sensor_noise.torque_noise_nm);
    EXPECT_EQ(y.sensor_noise.torque_bias_nm, x.sensor_noise.torque_bias_nm);
    EXPECT_EQ(y.sensor_noise.torque_filter_hz, x.sensor_noise.torque_filter_hz);
    EXPECT_EQ(y.sensor_noise.pressure_full_scale_pa, x.sensor_noise.pressure_full_scale_pa);
    EXPECT_EQ(y.sensor_noise.pressure_bits, x.sensor_noise.pressure_bits);
    EXPECT_EQ(y.sensor_noise.pressure_noise_pa, x.sensor_noise.pressure_noise_pa);
  }
}

TEST(PlantConfigYamlTest, APlantWithTwoFluidsIsRefused) {
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  PlantConfig a = loadPlantConfig(defaultPlantConfigPath(), model);
  a.joints[3].fluid.air_fraction = 0.01;
  try {
    static_cast<void>(formatPlantConfigYaml(a, model));
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint R_EB has another supply or fluid"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fullarm::plant
