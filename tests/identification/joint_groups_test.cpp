// Reduced groups of a plant joint against Merritt's formulas worked by hand for a rotary vane
// with pure oil (no entrained air): a = k_amp K_v sqrt((p_s - p_r)/2) / D, K_h = beta D^2 (1/V_a +
// 1/V_b), c = C_i / D^2.

#include "fullarm/identification/joint_groups.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/plant/hydraulics.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::identification {
namespace {

TEST(JointGroupsTest, RotaryVaneGroupsFollowMerrittsFormulas) {
  plant::JointParams j;
  j.actuator.kind = plant::ActuatorKind::kRotaryVane;
  j.actuator.displacement_m3_per_rad = 2.0e-6;
  j.actuator.inertia_kgm2 = 1.0e-4;
  j.valve.amplifier_gain_per_v = 0.1;
  j.valve.rated_flow_m3ps = 8.0e-6;
  j.valve.rated_pressure_drop_pa = 4.0e6;
  j.supply_pressure_pa = 20.0e6;
  j.return_pressure_pa = 0.0;
  j.fluid.oil_bulk_modulus_pa = 1.5e9;
  j.fluid.air_fraction = 0.0;
  j.chambers.dead_volume_a_m3 = 1.0e-6;
  j.chambers.dead_volume_b_m3 = 1.0e-6;
  j.chambers.internal_leakage_m3ps_per_pa = 4.0e-13;
  j.friction.coulomb_nm = 0.7;
  j.friction.static_nm = 0.9;
  j.friction.stribeck_velocity_radps = 0.04;
  j.friction.smoothing_velocity_radps = 0.02;
  j.valve.spool_stroke_m = 2.0e-4;
  j.valve.lap_pa_m = j.valve.lap_pb_m = j.valve.lap_at_m = j.valve.lap_bt_m = -1.0e-6;
  j.valve.edge_rounding_m = 4.0e-7;
  j.friction.viscous_nms_per_rad = 0.2;
  j.min_rad = -1.0;
  j.max_rad = 1.0;
  const double q = 0.5;
  const GreyModel m = greyModelFromJoint(j, q, 0.3, 4.0, 2);
  const double d = 2.0e-6;
  const double kv = 8.0e-6 / std::sqrt(4.0e6);
  EXPECT_NEAR(m.value[kFlowGain], 0.1 * kv * std::sqrt(10.0e6) / d, 1e-12);
  // Chambers: V_a = V0 + D (q - q_min) = 1e-6 + 2e-6 * 1.5, V_b = V0 + D (q_max - q) = 1e-6 + 2e-6 * 0.5.
  const double va = 1.0e-6 + 2.0e-6 * 1.5;
  const double vb = 1.0e-6 + 2.0e-6 * 0.5;
  EXPECT_NEAR(m.value[kStiffness], 1.5e9 * d * d * (1.0 / va + 1.0 / vb), 1e-6 * m.value[kStiffness]);
  EXPECT_NEAR(m.value[kLeakage], 4.0e-13 / (d * d), 1e-12);
  EXPECT_DOUBLE_EQ(m.value[kInertia], 0.3 + 1.0e-4);
  EXPECT_DOUBLE_EQ(m.value[kViscous], 0.2);
  EXPECT_DOUBLE_EQ(m.value[kCoulomb], 0.7);
  EXPECT_NEAR(m.value[kStribeck], 0.2, 1e-12);
  EXPECT_DOUBLE_EQ(m.stribeck_velocity_radps, 0.04);
  EXPECT_DOUBLE_EQ(m.coulomb_smoothing_radps, 0.02);
  // The valve's structure: stall torque D (p_s - p_r), the underlap and rounding over the
  // stroke per volt (2e-4 m x 0.1 / V = 2e-5 m/V).
  EXPECT_NEAR(m.stall_torque_nm, d * 20.0e6, 1e-9);
  EXPECT_NEAR(m.underlap_v, 0.05, 1e-12);
  EXPECT_NEAR(m.edge_rounding_v, 0.02, 1e-12);
  EXPECT_DOUBLE_EQ(m.value[kLoadTorque], 4.0);
  EXPECT_EQ(m.delay_samples, 2);
}

// The hydraulic torque of the chamber pressures: D (p_a - p_b) for a vane; for a cylinder
// R(q) (A_a p_a - A_b p_b), the moment arm the plant's lever gives, unequal areas counted (against
// the plant's own finite difference of the chamber volume). Pressures from a log with one chamber
// only, unequal lengths and a joint without hydraulics are refused.
TEST(JointGroupsTest, HydraulicTorqueIsTheChamberPressuresThroughTheGeometry) {
  plant::JointParams vane;
  vane.actuator.kind = plant::ActuatorKind::kRotaryVane;
  vane.actuator.displacement_m3_per_rad = 2.0e-6;
  vane.min_rad = -1.0;
  vane.max_rad = 1.0;
  const std::vector<double> tau = hydraulicTorque(vane, {0.0, 0.5}, {10.0e6, 3.0e6}, {4.0e6, 9.0e6});
  EXPECT_NEAR(tau[0], 2.0e-6 * 6.0e6, 1e-9);
  EXPECT_NEAR(tau[1], -2.0e-6 * 6.0e6, 1e-9);

  // The shipped elbow (a cylinder on a lever), with a rod side of two thirds of the cap's area.
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  plant::JointParams cylinder = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model).joints[3];
  ASSERT_EQ(cylinder.actuator.kind, plant::ActuatorKind::kCylinder);
  cylinder.actuator.piston_area_b_m2 = cylinder.actuator.piston_area_a_m2 * 2.0 / 3.0;
  const plant::StrokeRange range = plant::strokeRange(cylinder);
  for (const double q : {cylinder.min_rad + 0.2, 0.5 * (cylinder.min_rad + cylinder.max_rad), cylinder.max_rad - 0.2}) {
    const double h = 1e-6;
    const double dva =
        (plant::chamberVolumes(cylinder, range, q + h).v_a_m3 - plant::chamberVolumes(cylinder, range, q - h).v_a_m3) /
        (2.0 * h);
    const double dvb =
        (plant::chamberVolumes(cylinder, range, q + h).v_b_m3 - plant::chamberVolumes(cylinder, range, q - h).v_b_m3) /
        (2.0 * h);
    const double want = 12.0e6 * dva + 5.0e6 * dvb;
    EXPECT_NEAR(hydraulicTorque(cylinder, {q}, {12.0e6}, {5.0e6})[0], want, 1e-6 * std::abs(want)) << q;
    EXPECT_GT(dva, 0.0) << "chamber A drives q positive";
  }

  EXPECT_THROW((void)hydraulicTorque(vane, {0.0, 0.1}, {1.0e6}, {1.0e6, 1.0e6}), std::invalid_argument);
  plant::JointParams ideal = vane;
  ideal.actuator.kind = plant::ActuatorKind::kIdealTorque;
  EXPECT_THROW((void)hydraulicTorque(ideal, {0.0}, {1.0e6}, {1.0e6}), std::invalid_argument);
  SignalTable log;
  log.names = {"time_s", "q_rad", "pressure_b_pa"};
  log.columns = {{0.0, 0.001}, {0.1, 0.1}, {1.0e6, 1.0e6}};
  ExperimentData data;
  data.q_rad = {0.1, 0.1};
  try {
    addHydraulicTorque(data, log, vane);
    ADD_FAILURE() << "a log with one chamber's pressure was taken";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("no column pressure_a_pa"), std::string::npos) << e.what();
  }
  log.names[2] = "tau_other_nm";  // no pressures at all: nothing added
  addHydraulicTorque(data, log, vane);
  EXPECT_TRUE(data.tau_hydraulic_nm.empty());
}

}  // namespace
}  // namespace fullarm::identification
