// The closed-loop harness (controller + CVODES plant): the scenario's load against fullarm::arm,
// the minimum-jerk reference against its closed form, the rendered wall stiffness against the
// wall's K_w, oscillation detection on loops known to be unstable, computation delay, fault
// injection (safe valve null holds the joint) and bit-for-bit determinism.

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "design_fixture.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/design/closed_loop.hpp"
#include "fullarm/design/validation.hpp"

namespace fullarm::design {
namespace {

JointScenario scenario(std::string_view joint, controllers::ControllerKind kind) {
  JointScenario sc = makeJointScenario(test::dtsModel(), test::dtsPlant(), test::referenceGains(), joint);
  sc.kind = kind;
  return sc;
}

// The single-joint load is exact: g(q_k) = a cos q_k + b sin q_k with the rest of the arm fixed.
TEST(ClosedLoopScenario, LoadGravityAndInertiaMatchTheArmModel) {
  const arm::ArmModel& model = test::dtsModel();
  arm::ArmData data(model);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-3.0, 3.0);
  for (const char* name : {"SFE", "SAA", "HR", "EB", "WR", "WFE", "WAA"}) {
    const JointScenario sc = scenario(name, controllers::ControllerKind::kAdmittance);
    const int k = model.jointIndex(sc.joint_name);
    Eigen::VectorXd q = model.defaultPosture();
    q[k] = sc.start_rad;
    arm::computeMassMatrix(model, data, q);
    EXPECT_NEAR(sc.load.inertia_kgm2, data.mass_matrix(k, k) + sc.user.inertia_kgm2, 1e-12) << name;
    for (int trial = 0; trial < 5; ++trial) {
      q[k] = angle(rng);
      arm::computeGravityTorques(model, data, q);
      const double g = sc.load.gravity_cos_nm * std::cos(q[k]) + sc.load.gravity_sin_nm * std::sin(q[k]);
      EXPECT_NEAR(g, data.tau_gravity[k], 1e-9 * std::max(1.0, std::abs(g))) << name;
    }
    // The motion fits inside the joint limits.
    const double far =
        sc.start_rad + sc.direction * (sc.timing.free_move_rad + sc.timing.wall_gap_rad + sc.timing.push_rad);
    EXPECT_GT(far, sc.joint.min_rad) << name;
    EXPECT_LT(far, sc.joint.max_rad) << name;
  }
}

TEST(ClosedLoopScenario, MinimumJerkMatchesItsClosedForm) {
  const double T = 0.7;
  EXPECT_EQ(minimumJerk(-0.1, T).position, 0.0);
  EXPECT_EQ(minimumJerk(T + 0.1, T).position, 1.0);
  EXPECT_NEAR(minimumJerk(0.5 * T, T).position, 0.5, 1e-15);
  EXPECT_NEAR(minimumJerk(0.5 * T, T).rate_per_s, 1.875 / T, 1e-12);  // 30/16 at mid-course
  for (double t = 0.01; t < T; t += 0.05) {
    const double h = 1e-6;
    const double fd = (minimumJerk(t + h, T).position - minimumJerk(t - h, T).position) / (2 * h);
    EXPECT_NEAR(minimumJerk(t, T).rate_per_s, fd, 1e-7);
  }
}

// In contact, the user's torque over the penetration is the wall's stiffness (the arm comes to
// rest against the wall: user torque = wall torque = K_w p), for both controllers.
TEST(ClosedLoop, RendersTheWallStiffness) {
  for (controllers::ControllerKind kind :
       {controllers::ControllerKind::kAdmittance, controllers::ControllerKind::kTorquePid}) {
    for (const char* joint : {"EB", "WR"}) {
      const JointScenario sc = scenario(joint, kind);
      ClosedLoopTrace trace;
      const ClosedLoopResult r = simulateJoint(sc, &trace);
      ASSERT_TRUE(r.stable) << joint << " " << controllers::controllerKindName(kind) << ": " << r.failure;
      EXPECT_GT(r.contact_penetration_rad, 0.0);
      EXPECT_NEAR(r.contact_rendered_stiffness_nm_per_rad / sc.wall.stiffness_nm_per_rad, 1.0, 0.15)
          << joint << " " << controllers::controllerKindName(kind);
      // The user moved the joint the way the reference went (sign conventions end to end).
      const double travel = trace.q_rad[static_cast<std::size_t>(0.2 / sc.dt_s) + 1200] - sc.start_rad;
      EXPECT_GT(sc.direction * travel, 0.5 * sc.timing.free_move_rad) << joint;
    }
  }
}

// A torque loop at 4x the default gain oscillates near the hydraulic resonance; a wall 25x
// stiffer than nominal makes the admittance controller bounce. Both must be flagged.
TEST(ClosedLoop, DetectsOscillation) {
  JointScenario pid = scenario("EB", controllers::ControllerKind::kTorquePid);
  pid.gains.torque_pid.kp_v_per_nm *= 4.0;
  const ClosedLoopResult r1 = simulateJoint(pid);
  EXPECT_FALSE(r1.stable);
  EXPECT_TRUE(r1.oscillating);
  EXPECT_GT(r1.oscillation_frequency_hz, 30.0);

  JointScenario adm = scenario("EB", controllers::ControllerKind::kAdmittance);
  adm.wall.stiffness_nm_per_rad = 5000.0;
  const ClosedLoopResult r2 = simulateJoint(adm);
  EXPECT_FALSE(r2.stable);
  EXPECT_TRUE(r2.oscillating);
}

// Computation delay costs phase: a torque loop stable without delay oscillates with 3 samples.
TEST(ClosedLoop, ComputationDelayDestabilises) {
  JointScenario sc = scenario("EB", controllers::ControllerKind::kTorquePid);
  sc.gains.torque_pid.kp_v_per_nm = 0.2;
  sc.gains.torque_pid.ki_v_per_nms = 10.0;
  sc.delay_samples = 0;
  EXPECT_TRUE(simulateJoint(sc).stable);
  sc.delay_samples = 3;
  const ClosedLoopResult r = simulateJoint(sc);
  EXPECT_FALSE(r.stable);
  EXPECT_TRUE(r.oscillating);
}

// A load cell that fails mid-motion: the controller latches the fault and commands exactly 0 V
// from then on; the valve at null stops driving the joint, which slows to the slow sag that the
// underlapped valve's null leakage allows under gravity and the user's push (no hydraulic lock:
// docs/controllers.md, "Faults").
TEST(ClosedLoop, SensorFaultStopsTheJoint) {
  for (controllers::ControllerKind kind :
       {controllers::ControllerKind::kAdmittance, controllers::ControllerKind::kTorquePid}) {
    JointScenario sc = scenario("EB", kind);
    sc.inject_nan_torque_at_s = 0.45;  // mid free move, joint moving
    ClosedLoopTrace trace;
    const ClosedLoopResult r = simulateJoint(sc, &trace);
    EXPECT_FALSE(r.stable);
    EXPECT_TRUE(r.controller_faults & controllers::kFaultNonFiniteInput);
    const auto fault = static_cast<std::size_t>(0.45 / sc.dt_s);
    for (std::size_t i = fault; i < trace.valve_v.size(); ++i) ASSERT_EQ(trace.valve_v[i], 0.0) << i;
    // Still moving at the fault, held 0.3 s later while the user keeps pushing.
    EXPECT_GT(std::abs(trace.qd_radps[fault]), 0.1);
    const std::size_t later = fault + 300;
    double max_speed = 0.0, max_user = 0.0;
    for (std::size_t i = later; i < trace.qd_radps.size(); ++i) {
      max_speed = std::max(max_speed, std::abs(trace.qd_radps[i]));
      max_user = std::max(max_user, std::abs(trace.tau_user_nm[i]));
    }
    EXPECT_LT(max_speed, 0.3 * std::abs(trace.qd_radps[fault])) << controllers::controllerKindName(kind);
    EXPECT_GT(max_user, 2.0);  // the user really pushes on the unpowered joint
  }
}

TEST(ClosedLoop, RunsAreBitForBitRepeatable) {
  JointScenario sc = scenario("WFE", controllers::ControllerKind::kAdmittance);
  sc.gains.passivity.enabled = true;
  ClosedLoopTrace a, b;
  const ClosedLoopResult ra = simulateJoint(sc, &a);
  const ClosedLoopResult rb = simulateJoint(sc, &b);
  EXPECT_EQ(a.q_rad, b.q_rad);
  EXPECT_EQ(a.valve_v, b.valve_v);
  EXPECT_EQ(ra.free_rms_user_torque_nm, rb.free_rms_user_torque_nm);
  EXPECT_EQ(ra.solver_steps, rb.solver_steps);
}

// The same Monte-Carlo on 1 and on 2 threads gives bit-identical runs.
TEST(MonteCarlo, ResultsDoNotDependOnTheThreadCount) {
  ValidationConfig config = loadValidationConfig(defaultValidationConfigPath());
  config.samples = 4;
  const std::vector<JointScenario> nominal = {
      makeJointScenario(test::dtsModel(), test::dtsPlant(), test::referenceGains(), "WFE"),
      makeJointScenario(test::dtsModel(), test::dtsPlant(), test::referenceGains(), "EB")};
  const std::vector<JointMonteCarlo> one = runMonteCarlo(nominal, config, 1);
  const std::vector<JointMonteCarlo> two = runMonteCarlo(nominal, config, 2);
  ASSERT_EQ(one.size(), 2u);
  for (std::size_t j = 0; j < one.size(); ++j) {
    ASSERT_EQ(one[j].runs.size(), 4u);
    EXPECT_EQ(one[j].failures, two[j].failures);
    EXPECT_EQ(one[j].worst, two[j].worst);
    for (std::size_t i = 0; i < one[j].runs.size(); ++i) {
      EXPECT_EQ(one[j].runs[i].result.free_rms_user_torque_nm, two[j].runs[i].result.free_rms_user_torque_nm);
      EXPECT_EQ(one[j].runs[i].result.contact_hold_speed_rms_radps, two[j].runs[i].result.contact_hold_speed_rms_radps);
      EXPECT_EQ(one[j].runs[i].sample.delay_samples, two[j].runs[i].sample.delay_samples);
    }
  }
  // A joint's samples do not depend on which other joints run with it.
  const std::vector<JointMonteCarlo> alone = runMonteCarlo({nominal[1]}, config, 2);
  EXPECT_EQ(alone[0].runs[2].sample.bulk_modulus_scale, one[1].runs[2].sample.bulk_modulus_scale);
  EXPECT_EQ(alone[0].runs[2].result.free_rms_user_torque_nm, one[1].runs[2].result.free_rms_user_torque_nm);
}

}  // namespace
}  // namespace fullarm::design
