// One hydraulic joint against analytic hydraulics (Merritt, Hydraulic Control Systems;
// docs/sources.md, Plant 1.6): natural frequency, pressure build-up, no-load velocity,
// passivity. Every oracle here is a closed-form formula, not the plant code.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "fullarm/arm/actuator.hpp"
#include "plant_fixture.hpp"
#include "plant_test_util.hpp"

namespace fullarm::plant {
namespace {

using test::PlantTolerance;

// Every check runs with each integrator: CVODES (the reference) and Rodas3.
class JointPhysics : public ::testing::TestWithParam<IntegratorKind> {
 protected:
  [[nodiscard]] SolverOptions options() const {
    SolverOptions o;
    o.integrator = GetParam();
    return o;
  }
  [[nodiscard]] SolverOptions tightOptions() const;
};

SolverOptions JointPhysics::tightOptions() const {
  SolverOptions o = options();
  o.rtol = 1e-8;
  o.atol_pressure_pa = 1.0;
  o.atol_angle_rad = 1e-10;
  o.atol_velocity_radps = 1e-8;
  return o;
}

// The cylinder geometry from a shared sin q, cos q (angle addition with the lever offset, as the
// plant's right-hand side uses it) against fullarm::arm's cylinder length and moment arm, the slope
// against central differences of that moment arm, and the single-angle form to rounding, for every
// joint of the DTS configuration over its range and a little beyond.
TEST(ActuatorGeometry, SharedSinCosFormMatchesTheArmModelsCylinder) {
  int cylinders = 0;
  for (const JointParams& p : test::dtsPlant().joints) {
    SCOPED_TRACE(p.name);
    const SinCos offset = leverOffsetSinCos(p.actuator);
    const StrokeRange range = strokeRange(p);
    const bool cylinder = p.actuator.kind == ActuatorKind::kCylinder;
    cylinders += cylinder ? 1 : 0;
    for (int i = 0; i <= 40; ++i) {
      const double q = p.min_rad - 0.05 + (p.max_rad - p.min_rad + 0.1) * i / 40.0;
      const SinCos q_sincos{std::sin(q), std::cos(q)};
      const ActuatorKinematics shared = actuatorKinematics(p.actuator, q, q_sincos, offset);
      const ActuatorKinematics direct = actuatorKinematics(p.actuator, q);
      if (!cylinder) {
        EXPECT_EQ(shared.stroke, q);
        EXPECT_EQ(shared.ratio, 1.0);
        EXPECT_EQ(shared.ratio_slope, 0.0);
        continue;
      }
      const double length = arm::cylinderLength(p.actuator.lever, q);
      const double arm_m = arm::actuatorMomentArm(p.actuator.lever, q);
      constexpr double kStep = 1e-6;
      const double slope =
          (arm::actuatorMomentArm(p.actuator.lever, q + kStep) - arm::actuatorMomentArm(p.actuator.lever, q - kStep)) /
          (2.0 * kStep);
      EXPECT_NEAR(shared.stroke, length, 1e-14 * length);
      EXPECT_NEAR(shared.ratio, arm_m, 1e-12 * std::abs(length));
      EXPECT_NEAR(shared.ratio_slope, slope, 1e-8 * std::abs(length));
      EXPECT_NEAR(shared.stroke, direct.stroke, 1e-15 * length);
      EXPECT_NEAR(shared.ratio, direct.ratio, 1e-14 * std::abs(length));
      EXPECT_NEAR(shared.ratio_slope, direct.ratio_slope, 1e-13 * std::abs(length));
      const ChamberVolumes v = chamberVolumes(p, range, q, q_sincos, offset);
      const ChamberVolumes w = chamberVolumes(p, range, q);
      EXPECT_NEAR(v.v_a_m3, w.v_a_m3, 1e-13 * w.v_a_m3);
      EXPECT_NEAR(v.v_b_m3, w.v_b_m3, 1e-13 * w.v_b_m3);
      EXPECT_NEAR(v.dva_dq, w.dva_dq, 1e-13 * std::abs(w.dva_dq) + 1e-25);
    }
  }
  EXPECT_EQ(cylinders, 5);  // SFE, SAA, EB, WFE, WAA
}

// Blocked spool (valve overlapped, closed), impulse in velocity: the joint rings at
// omega_h = sqrt(4 beta D^2 / (V_t J)) (docs/sources.md, Plant 1.6).
TEST_P(JointPhysics, BlockedSpoolImpulseRingsAtHydraulicNaturalFrequency) {
  JointParams p = test::vaneJoint();
  p.valve.lap_pa_m = p.valve.lap_pb_m = p.valve.lap_at_m = p.valve.lap_bt_m = 1e-5;  // closed at null
  const RigidLoad load{0.05, 0.0, 0.0};
  ArmPlant plant;
  plant.configure(p, load, tightOptions());
  JointState s0;
  s0.p_a_pa = s0.p_b_pa = 10e6;
  s0.qd_radps = 0.05;
  plant.reset({s0});
  const double beta = p.fluid.oil_bulk_modulus_pa;
  const double D = p.actuator.displacement_m3_per_rad;
  const double vt = 6e-6;
  const double f_expected_hz = std::sqrt(4.0 * beta * D * D / (vt * load.inertia_kgm2)) / (2.0 * std::numbers::pi);
  const PlantCommand cmd = PlantCommand::zero(1);
  const double dt = 1e-5;
  std::vector<double> crossings;
  double q_prev = plant.state(0).q_rad;
  for (int k = 0; k < 20000; ++k) {
    ASSERT_TRUE(plant.step(dt, cmd).ok()) << plant.lastError();
    const double q = plant.state(0).q_rad;
    if (q_prev > 0.0 && q <= 0.0) crossings.push_back(plant.time() - dt * q / (q - q_prev));
    q_prev = q;
  }
  ASSERT_GE(crossings.size(), 5u);
  const double period = (crossings.back() - crossings.front()) / static_cast<double>(crossings.size() - 1);
  EXPECT_NEAR(1.0 / period, f_expected_hz, PlantTolerance::kNaturalFrequency * f_expected_hz);
  EXPECT_NEAR(f_expected_hz, 45.9, 0.1);  // the worked example of docs/sources.md, Plant 1.6
}

// Blocked load, small opening: dP_L/dt = 4 beta Q_L / V_t with Q_L = K_v x sqrt(p_s - p_a).
TEST_P(JointPhysics, BlockedLoadPressureBuildUpRate) {
  const JointParams p = test::vaneJoint();
  const RigidLoad load{1e12, 0.0, 0.0};  // blocked
  ArmPlant plant;
  plant.configure(p, load, tightOptions());
  const double x = 0.02;
  JointState s0;
  s0.spool = x;
  s0.p_a_pa = s0.p_b_pa = 0.5 * (p.supply_pressure_pa + p.return_pressure_pa);
  plant.reset({s0});
  PlantCommand cmd = PlantCommand::zero(1);
  cmd.command[0] = x / p.valve.amplifier_gain_per_v;
  const double dt = 2e-5;
  ASSERT_TRUE(plant.step(dt, cmd).ok()) << plant.lastError();
  const JointState s = plant.state(0);
  const double rate = ((s.p_a_pa - s.p_b_pa) - 0.0) / dt;
  const double kv = p.valve.rated_flow_m3ps / std::sqrt(p.valve.rated_pressure_drop_pa);
  const double q_l = kv * x * std::sqrt(p.supply_pressure_pa - s0.p_a_pa);
  const double expected = 4.0 * p.fluid.oil_bulk_modulus_pa * q_l / 6e-6;
  EXPECT_NEAR(rate, expected, PlantTolerance::kBuildUpRate * expected);
}

// No load: steady velocity Q_L / D at three openings, Q_L = K_v x sqrt((p_s - p_r)/2).
TEST_P(JointPhysics, NoLoadSteadyVelocityAtThreeOpenings) {
  const JointParams p = test::vaneJoint();
  const double kv = p.valve.rated_flow_m3ps / std::sqrt(p.valve.rated_pressure_drop_pa);
  for (const double x : {0.05, 0.1, 0.2}) {
    ArmPlant plant;
    plant.configure(p, RigidLoad{0.05, 0.0, 0.0}, options());
    JointState s0;
    s0.spool = x;
    s0.q_rad = -0.9;
    s0.p_a_pa = s0.p_b_pa = 0.5 * (p.supply_pressure_pa + p.return_pressure_pa);
    plant.reset({s0});
    PlantCommand cmd = PlantCommand::zero(1);
    cmd.command[0] = x / p.valve.amplifier_gain_per_v;
    const double expected =
        kv * x * std::sqrt(0.5 * (p.supply_pressure_pa - p.return_pressure_pa)) / p.actuator.displacement_m3_per_rad;
    double q_start = 0.0;
    const int steps = 800;
    for (int k = 0; k < steps; ++k) {
      ASSERT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
      if (k == steps - 201) q_start = plant.state(0).q_rad;
    }
    const double v = (plant.state(0).q_rad - q_start) / 0.2;  // mean over the last 0.2 s
    EXPECT_NEAR(v, expected, PlantTolerance::kNoLoadVelocity * expected) << "opening " << x;
    EXPECT_LT(plant.state(0).q_rad, p.max_rad);
  }
}

// Valve closed, no leakage: hydraulic + kinetic + gravity + stop energy never increases.
TEST_P(JointPhysics, ClosedValveIsPassive) {
  JointParams p = test::vaneJoint();
  p.valve.lap_pa_m = p.valve.lap_pb_m = p.valve.lap_at_m = p.valve.lap_bt_m = 1e-5;
  p.friction = {0.5, 0.8, 0.05, 0.05, 1e-3};
  const RigidLoad load{0.05, 3.0, -1.0};
  const double beta = p.fluid.oil_bulk_modulus_pa;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> pressure(p.return_pressure_pa, p.supply_pressure_pa);
  for (int trial = 0; trial < 3; ++trial) {
    ArmPlant plant;
    plant.configure(p, load, tightOptions());
    JointState s0;
    s0.p_a_pa = pressure(rng);
    s0.p_b_pa = pressure(rng);
    s0.q_rad = 0.5;
    plant.reset({s0});
    const StrokeRange range = strokeRange(p);
    auto energy = [&] {
      const JointState s = plant.state(0);
      const ChamberVolumes v = chamberVolumes(p, range, s.q_rad);
      const double pen = std::max(s.q_rad - p.max_rad, 0.0) + std::max(p.min_rad - s.q_rad, 0.0);
      // gravity potential: integral of g(q) = a cos q + b sin q
      const double v_grav = load.gravity_cos_nm * std::sin(s.q_rad) - load.gravity_sin_nm * std::cos(s.q_rad);
      return test::chamberEnergy(v.v_a_m3, s.p_a_pa, beta) + test::chamberEnergy(v.v_b_m3, s.p_b_pa, beta) +
             0.5 * load.inertia_kgm2 * s.qd_radps * s.qd_radps + v_grav +
             0.5 * p.hard_stop.stiffness_nm_per_rad * pen * pen;
    };
    const double e0 = energy();
    double e_prev = e0;
    double worst_rise = 0.0;
    const PlantCommand cmd = PlantCommand::zero(1);
    for (int k = 0; k < 5000; ++k) {
      ASSERT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
      const double e = energy();
      worst_rise = std::max(worst_rise, e - e_prev);
      e_prev = e;
    }
    EXPECT_LE(worst_rise, 1e-7 * std::abs(e0)) << "trial " << trial << " E0 = " << e0;
    EXPECT_LT(e_prev, e0);  // friction dissipated something
  }
}

INSTANTIATE_TEST_SUITE_P(Integrators, JointPhysics,
                         ::testing::Values(IntegratorKind::kCvodes, IntegratorKind::kRodas3, IntegratorKind::kRodas4,
                                           IntegratorKind::kRos34pw2),
                         [](const ::testing::TestParamInfo<IntegratorKind>& param_info) {
                           return param_info.param == IntegratorKind::kCvodes   ? "Cvodes"
                                  : param_info.param == IntegratorKind::kRodas3 ? "Rodas3"
                                  : param_info.param == IntegratorKind::kRodas4 ? "Rodas4"
                                                                                : "Ros34pw2";
                         });

}  // namespace
}  // namespace fullarm::plant
