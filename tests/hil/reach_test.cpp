// The scripted user reaches through the valve scene's opening on the simulated DTS (lockstep):
// in full-arm mode the hand reaches the wheel and no link touches the scene; in hand-only mode
// a link other than the hand penetrates the opening's frame (depth and duration recorded). The
// missed-contact oracle counts no miss in either, and fires when the global result arrives too
// late for the look-ahead L - d_f.

#include <gtest/gtest.h>

#include "fullarm/haptics/contact_forces.hpp"
#include "hil_fixture.hpp"
#include "run_fixture.hpp"

namespace fullarm::hil {
namespace {

constexpr double kReachDuration_s = 30.0;
/// The stated margin: no link deeper into the scene than this [m].
constexpr double kPenetrationMargin_m = 1e-3;
/// "Reached": the hand point within this of the path's end at the wheel [m].
constexpr double kReachTolerance_m = 0.03;

const RunResult& reach(haptics::RenderMode mode) {
  static const RunResult full = runHil(test::shippedRun(kReachDuration_s, haptics::RenderMode::kFullArm));
  static const RunResult hand = runHil(test::shippedRun(kReachDuration_s, haptics::RenderMode::kHandOnly));
  return mode == haptics::RenderMode::kFullArm ? full : hand;
}

TEST(Reach, FullArmReachesTheValveWithoutPenetration) {
  const RunResult& r = reach(haptics::RenderMode::kFullArm);
  ASSERT_FALSE(r.tripped) << supervisorCauseName(r.trip_cause);
  EXPECT_LT(r.hand_to_target_m, kReachTolerance_m);
  // The user never pushes harder than k d_f (20 N): a single spring can hold the push.
  EXPECT_LE(r.max_user_force_n, 15.0 + 1e-9);
  ASSERT_TRUE(r.oracle_ran);
  EXPECT_EQ(r.oracle_ticks, r.telemetry.size());
  for (std::size_t l = 0; l < r.link_names.size(); ++l) {
    EXPECT_LE(r.link_max_penetration_m[l], kPenetrationMargin_m) << r.link_names[l];
    EXPECT_GT(r.link_min_distance_m[l], 0.0) << r.link_names[l] << " touched the scene";
  }
  EXPECT_EQ(r.missed_contact_ticks, 0u);
  // The path goes near the scene: contacts were rendered.
  int contact_ticks = 0;
  for (const TickTelemetry& t : r.telemetry) contact_ticks += t.active_springs > 0 ? 1 : 0;
  EXPECT_GT(contact_ticks, 1000);
}

TEST(Reach, HandOnlyLetsTheForearmPenetrateTheFrame) {
  const RunResult& r = reach(haptics::RenderMode::kHandOnly);
  const arm::ArmModel& model = test::model();
  ASSERT_FALSE(r.tripped) << supervisorCauseName(r.trip_cause);
  bool non_hand_penetrated = false;
  for (std::size_t l = 0; l < r.link_names.size(); ++l) {
    if (haptics::isHandLink(model, static_cast<int>(l))) continue;
    if (r.link_max_penetration_m[l] > kPenetrationMargin_m) {
      non_hand_penetrated = true;
      EXPECT_GT(r.link_penetration_s[l], 0.1) << r.link_names[l];  // the duration is recorded
    }
  }
  EXPECT_TRUE(non_hand_penetrated);
  // The tick's own records see the same: contact depth on a non-hand link.
  double deepest = 0.0;
  for (const TickTelemetry& t : r.telemetry) {
    for (int l = 0; l < t.num_config; ++l) {
      if (!haptics::isHandLink(model, l)) deepest = std::max(deepest, t.link_depth_m[static_cast<std::size_t>(l)]);
    }
  }
  EXPECT_GT(deepest, 0.0);
  EXPECT_EQ(r.missed_contact_ticks, 0u);
}

TEST(Reach, TheOracleFiresWhenTheGlobalResultArrivesTooLateForTheLookAhead) {
  RunOptions o = test::shippedRun(12.0);
  o.delivery_delay_ticks = 1500;  // 1.5 s: the arm sweeps far beyond L - d_f meanwhile
  const RunResult r = runHil(o);
  EXPECT_GT(r.missed_contact_ticks, 0u);
  EXPECT_GT(r.sweep_exceeded_ticks, 0u);
  ASSERT_FALSE(r.missed_contacts.empty());
  EXPECT_LT(r.missed_contacts.front().distance_m, 0.01);
}

TEST(Reach, LockstepIsBitIdenticalForASeedAndReplaysBitForBit) {
  HilSession a(test::shippedRun(3.0));
  HilSession b(test::shippedRun(3.0));
  RunOptions other = test::shippedRun(3.0);
  other.seed = 2;
  const RunResult ra = a.run();
  const RunResult rb = b.run();
  const RunResult rc = runHil(other);
  ASSERT_EQ(ra.telemetry.size(), rb.telemetry.size());
  bool differs_with_seed = false;
  for (std::size_t k = 0; k < ra.telemetry.size(); ++k) {
    const TickTelemetry& x = ra.telemetry[k];
    const TickTelemetry& y = rb.telemetry[k];
    ASSERT_EQ(x.valve_v, y.valve_v) << "tick " << k;
    ASSERT_EQ(x.tau_contact_nm, y.tau_contact_nm) << "tick " << k;
    ASSERT_EQ(x.q_rad, y.q_rad) << "tick " << k;
    ASSERT_EQ(x.tau_load_cell_nm, y.tau_load_cell_nm) << "tick " << k;
    differs_with_seed = differs_with_seed || x.tau_load_cell_nm != rc.telemetry[k].tau_load_cell_nm;
  }
  EXPECT_TRUE(differs_with_seed) << "the seed drives the sensor noise";
  // Replay through a fresh tick.
  const std::vector<TickTelemetry> replayed = a.replay(ra);
  ASSERT_EQ(replayed.size(), ra.telemetry.size());
  for (std::size_t k = 0; k < replayed.size(); ++k) {
    ASSERT_EQ(replayed[k].valve_v, ra.telemetry[k].valve_v) << "tick " << k;
    ASSERT_EQ(replayed[k].tau_contact_nm, ra.telemetry[k].tau_contact_nm) << "tick " << k;
    ASSERT_EQ(replayed[k].tau_gravity_nm, ra.telemetry[k].tau_gravity_nm) << "tick " << k;
  }
}

}  // namespace
}  // namespace fullarm::hil
