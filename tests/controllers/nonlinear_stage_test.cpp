// The validation detector's two new criteria and the tuner's nonlinear verification stage.
// Oracles: the plant's sensor noise figure (the rendered wall torque's noise floor B_w * std of a
// backward-difference speed), the user's push against the joint's static friction read from the
// configuration, an independent Monte-Carlo of validate's own runner on draws the stage never saw,
// and bit-for-bit repetition.

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "controllers_fixture.hpp"
#include "fullarm/controllers/closed_loop.hpp"
#include "fullarm/controllers/nonlinear_stage.hpp"
#include "fullarm/controllers/validation.hpp"

namespace fullarm::controllers {
namespace {

ValidationConfig defaultValidation() {
  return loadValidationConfig(defaultValidationConfigPath());
}

// Fixed, hand-sized EB gains (the conservative defaults of commit 784533d: J_m 0.2, B_m 12,
// K_m 20, lambda 300, B_o/eps = 5/48), so that these tests do not move with config/dts_gains.yaml.
GainsConfig handSized() {
  GainsConfig g = test::referenceGains();
  JointGains& eb = g.joints[static_cast<std::size_t>(findGainsJoint(g, "R_EB"))];
  eb.impedance = {0.2, 12.0, 20.0};
  eb.sliding_mode = {300.0, 5.0, 48.0};
  return g;
}

JointScenario validationEb(const GainsConfig& gains) {
  return validationScenario(makeJointScenario(test::dtsModel(), test::dtsPlant(), gains, "EB"), defaultValidation());
}

// Against a resting arm the rendered wall torque carries the sensor noise through the wall's
// damping (B_w times the backward-difference speed of a noisy angle: sqrt(2) sigma / T for white
// noise of sigma); the chatter criterion must judge the true motion instead.
TEST(ValidationDetector, ChatterIsJudgedOnTheTrueMotionNotOnTheSensorNoiseFloor) {
  JointScenario sc = validationEb(handSized());
  sc.wall.damping_nms_per_rad = 3.0;
  ClosedLoopTrace trace;
  const ClosedLoopResult r = simulateJoint(sc, &trace);
  const double sigma = sc.joint.sensor_noise.angle_noise_rad;
  const double noise_floor_nm = sc.wall.damping_nms_per_rad * std::sqrt(2.0) * sigma / sc.dt_s;
  ASSERT_TRUE(r.wall_reached) << r.failure;
  // The rendered torque is at least as noisy as the white-noise floor (quantisation adds to it).
  EXPECT_GT(r.contact_rendered_wall_torque_deviation_nm, 0.8 * noise_floor_nm);
  EXPECT_GT(r.contact_rendered_wall_torque_deviation_nm, 0.5);  // the old criterion's floor: would flag
  // The true wall torque of the resting arm varies far less.
  EXPECT_LT(r.contact_wall_torque_deviation_nm, 0.25 * r.contact_rendered_wall_torque_deviation_nm);
  EXPECT_TRUE(r.acceptable()) << r.failure;
}

// A device whose model damping is huge cannot follow the user's push: the wall is never reached
// although the push is far above the breakaway friction - a failure ("too sluggish"). A user who
// does not push (K_h = B_h = 0) does not reach the wall either, and that is no failure.
TEST(ValidationDetector, SluggishGainsFailButAUserWhoDoesNotPushDoesNot) {
  GainsConfig g = handSized();
  g.joints[static_cast<std::size_t>(findGainsJoint(g, "R_EB"))].impedance.damping_nms_per_rad = 2000.0;
  JointScenario sc = validationEb(g);
  const double breakaway = sc.joint.friction.static_nm;
  const ClosedLoopResult pushed = simulateJoint(sc);
  EXPECT_TRUE(pushed.stable) << pushed.failure;
  EXPECT_FALSE(pushed.wall_reached);
  EXPECT_GT(pushed.contact_user_torque_nm, 2.0 * breakaway);
  EXPECT_TRUE(pushed.sluggish);
  EXPECT_FALSE(pushed.acceptable());

  sc.user.stiffness_nm_per_rad = 0.0;
  sc.user.damping_nms_per_rad = 0.0;
  const ClosedLoopResult idle = simulateJoint(sc);
  EXPECT_FALSE(idle.wall_reached);
  EXPECT_LT(idle.contact_user_torque_nm, 2.0 * breakaway);
  EXPECT_FALSE(idle.sluggish);
  EXPECT_TRUE(idle.acceptable()) << idle.failure;
}

// A first contact inside the last window (the wall torque rising from zero once) is not chatter;
// the criterion needs contact made and then lost. Oracle: the trace's own wall torque.
TEST(ValidationDetector, ALateFirstContactIsNotChatter) {
  JointScenario sc = validationEb(handSized());
  sc.timing.contact_hold_s = 0.35;  // the last window (0.5 s) begins before the wall is reached
  ClosedLoopTrace trace;
  const ClosedLoopResult r = simulateJoint(sc, &trace);
  ASSERT_GT(r.contact_wall_torque_nm, 0.0) << r.failure;
  const std::size_t n = trace.tau_env_nm.size();
  const auto window = static_cast<std::size_t>(std::lround(sc.timing.detect_window_s / sc.dt_s));
  EXPECT_EQ(trace.tau_env_nm[n - window], 0.0);  // no contact at the start of the window
  EXPECT_FALSE(r.contact_lost);
  // The old criterion (deviation above half the mean and 0.5 N m) alone would have flagged it.
  EXPECT_GT(r.contact_wall_torque_deviation_nm, 0.5);
  EXPECT_GT(r.contact_wall_torque_deviation_nm, 0.5 * r.contact_wall_torque_nm);
  // (The window still holds the end of the move, so the speed criterion may object; chatter not.)
  EXPECT_EQ(r.failure.find("chatter"), std::string::npos) << r.failure;
}

TEST(NonlinearStage, SamplesAreItsOwnStreamInsideTheRangesAndRepeatable) {
  const ValidationConfig vc = defaultValidation();
  const auto a = stageSamples(vc.ranges, vc.seed, "R_EB", 0, 40);
  const auto b = stageSamples(vc.ranges, vc.seed, "R_EB", 0, 40);
  const auto other = stageSamples(vc.ranges, vc.seed, "R_WR", 0, 40);
  ASSERT_EQ(a.size(), 40u);
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].user_stiffness_nm_per_rad, b[i].user_stiffness_nm_per_rad);
    EXPECT_NE(a[i].user_stiffness_nm_per_rad, other[i].user_stiffness_nm_per_rad);
    EXPECT_GE(a[i].bulk_modulus_scale, vc.ranges.bulk_modulus_scale.min);
    EXPECT_LE(a[i].bulk_modulus_scale, vc.ranges.bulk_modulus_scale.max);
    EXPECT_GE(a[i].delay_samples, vc.ranges.delay_min_samples);
    EXPECT_LE(a[i].delay_samples, vc.ranges.delay_max_samples);
    // Not validate's draws of any slot's run i (validate hashes the name; compare with a direct draw).
    for (int slot = 0; slot < 4; ++slot) {
      EXPECT_NE(a[i].user_stiffness_nm_per_rad,
                drawSample(vc.ranges, vc.seed, slot, static_cast<int>(i)).user_stiffness_nm_per_rad);
    }
  }
}

// A "linear optimum" that oscillates on the nonlinear plant (8x the default output gain B_o/eps)
// is rejected in favour of the starting gains; the result is checked by validate's own runner on
// draws the stage never saw, where the rejected candidate fails. The stage is deterministic.
TEST(NonlinearStage, RejectsAnOscillatingCandidateAndIsDeterministic) {
  const ValidationConfig vc = defaultValidation();
  const JointScenario sc = validationEb(handSized());
  JointGains bad = sc.gains;
  bad.sliding_mode.boundary_layer_radps /= 8.0;
  NonlinearStageOptions o;
  o.samples = 6;
  o.check_samples = 6;
  o.rounds = 1;
  o.max_evaluations = 4;
  const NonlinearStageResult first = refineNonlinear(sc, bad, sc.gains, vc.ranges, vc.linear, o);
  const NonlinearStageResult second = refineNonlinear(sc, bad, sc.gains, vc.ranges, vc.linear, o);
  EXPECT_GT(first.linear_optimum.cost, first.start.cost);
  EXPECT_EQ(first.gains.impedance.damping_nms_per_rad, second.gains.impedance.damping_nms_per_rad);
  EXPECT_EQ(first.gains.sliding_mode.boundary_layer_radps, second.gains.sliding_mode.boundary_layer_radps);
  EXPECT_EQ(first.final_score.cost, second.final_score.cost);
  EXPECT_EQ(first.simulations, second.simulations);

  ValidationConfig check = vc;
  check.samples = 12;
  check.seed = 12345;
  JointScenario chosen = sc;
  chosen.gains = first.gains;
  JointScenario rejected = sc;
  rejected.gains = bad;
  const auto mc = runMonteCarlo({chosen, rejected}, check, 2);
  EXPECT_LT(mc[0].failures, mc[1].failures);
  EXPECT_GT(mc[1].failures, 0);
}

}  // namespace
}  // namespace fullarm::controllers
