// Fault injection on lockstep runs of the simulated DTS: each fault ends in its documented safe
// state (docs/hil.md, "Safety") with its cause and time in the run's events and in its LCM log
// (read back from the file): a latched trip puts
// every valve at null from that tick on and the device in its fault state with the enable line
// still; a stalled global search fades the contact torques to zero no faster than the
// configured rate.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <string>
#include <variant>
#include <vector>

#include "fullarm/hil/log_records.hpp"
#include "fullarm/hil/run_log.hpp"
#include "hil_fixture.hpp"
#include "run_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::hil {
namespace {

constexpr std::uint64_t kFaultTick = 500;

RunOptions faultRun(double duration_s = 1.0) {
  RunOptions o = test::shippedRun(duration_s);
  o.oracle = false;
  return o;
}

// The same run, writing its LCM log into a fresh scratch folder.
RunOptions logged(RunOptions o, const std::string& name) {
  o.log = fullarm::test::scratchDir("hil_fault_" + name) / "run.lcmlog";
  return o;
}

// The supervisor events of a run's LCM log, read back from the file.
std::vector<fullarm_lcm::supervisor_event_t> loggedEvents(const std::filesystem::path& log) {
  std::vector<fullarm_lcm::supervisor_event_t> events;
  RunLogReader reader(log);
  RunLogEntry entry;
  while (reader.next(entry)) {
    if (const auto* e = std::get_if<fullarm_lcm::supervisor_event_t>(&entry.message)) events.push_back(*e);
  }
  EXPECT_FALSE(reader.truncated()) << reader.warning();
  return events;
}

// Runs `options` with `hooks`; checks the latched trip with `cause` no earlier than `earliest`
// and the safe state from that tick on.
void expectLatchedTrip(const RunOptions& unlogged, const RunHooks& hooks, SupervisorCause cause,
                       std::uint64_t earliest = kFaultTick) {
  const RunOptions options =
      logged(unlogged, ::testing::UnitTest::GetInstance()->current_test_info()->name());
  HilSession session(options);
  const RunResult r = session.run(hooks);
  ASSERT_TRUE(r.tripped);
  EXPECT_EQ(r.trip_cause, cause) << supervisorCauseName(r.trip_cause);
  std::uint64_t trip_tick = 0;
  for (const SupervisorEvent& e : r.events) {
    if (e.trip) {
      trip_tick = e.tick;
      EXPECT_EQ(e.cause, cause) << "the first trip names the cause";
      EXPECT_DOUBLE_EQ(e.t_s, static_cast<double>(e.tick) * 1e-3) << "and its time";
      break;
    }
  }
  ASSERT_GE(trip_tick, earliest);
  // The log holds the same trip: its cause, its tick and a fault (or E-stop) severity.
  bool trip_logged = false;
  for (const fullarm_lcm::supervisor_event_t& e : loggedEvents(options.log)) {
    if (e.severity >= static_cast<std::int8_t>(EventSeverity::kFault)) {
      EXPECT_EQ(e.cause_code, static_cast<int>(cause)) << e.message;
      EXPECT_EQ(static_cast<std::uint64_t>(e.tick), trip_tick);
      EXPECT_FALSE(e.message.empty());
      trip_logged = true;
      break;
    }
  }
  EXPECT_TRUE(trip_logged) << "the trip is in the LCM log";
  // Forces were on before the fault ...
  bool driven_before = false;
  for (std::uint64_t k = 300; k + 1 < trip_tick; ++k) {
    for (const double v : r.telemetry[k].valve_v) driven_before = driven_before || v != 0.0;
  }
  EXPECT_TRUE(driven_before);
  // ... and every valve is at null from the trip on.
  for (std::uint64_t k = trip_tick - 1; k < r.telemetry.size(); ++k) {
    for (const double v : r.telemetry[k].valve_v) ASSERT_EQ(v, 0.0) << "tick " << k + 1;
    ASSERT_EQ(r.telemetry[k].supervisor_state, SupervisorState::kTripped);
  }
  // The device holds its safe outputs with the enable line still.
  EXPECT_EQ(session.device().state(), IoState::kFault) << "the device stays in its fault state";
  EXPECT_EQ(session.device().appliedCommand(), IoVector::Zero(session.device().numJoints()));
  EXPECT_FALSE(session.device().enableAsserted());
}

TEST(FaultInjection, NanReading) {
  RunHooks hooks;
  hooks.before_tick = [](std::uint64_t k, JointSample& s, SupervisorRequests&) {
    if (k == kFaultTick) s.tau_load_cell_nm[2] = std::numeric_limits<double>::quiet_NaN();
  };
  expectLatchedTrip(faultRun(), hooks, SupervisorCause::kSensorNonFinite);
}

TEST(FaultInjection, OutOfRangeReading) {
  RunHooks hooks;
  hooks.before_tick = [](std::uint64_t k, JointSample& s, SupervisorRequests&) {
    if (k == kFaultTick) {
      s.q_rad[1] = std::numeric_limits<double>::quiet_NaN();
      s.out_of_range_mask |= 1u << 1;
    }
  };
  expectLatchedTrip(faultRun(), hooks, SupervisorCause::kSensorOutOfRange);
}

TEST(FaultInjection, ValveCommandBeyondItsLimit) {
  RunHooks hooks;
  hooks.after_tick = [](std::uint64_t k, IoVector& valve) {
    if (k == kFaultTick) valve[3] = 12.0;
  };
  expectLatchedTrip(faultRun(), hooks, SupervisorCause::kValveCommandLimit);
}

TEST(FaultInjection, OverrunBurst) {
  RunHooks hooks;
  hooks.extra_compute_s = [](std::uint64_t k) { return k >= kFaultTick && k < kFaultTick + 30 ? 2e-3 : 0.0; };
  expectLatchedTrip(faultRun(), hooks, SupervisorCause::kOverrun, kFaultTick + 10);
}

TEST(FaultInjection, ShortOverrunBurstBelowTheLimitDoesNotTrip) {
  RunHooks hooks;
  hooks.extra_compute_s = [](std::uint64_t k) { return k >= kFaultTick && k < kFaultTick + 5 ? 2e-3 : 0.0; };
  const RunResult r = runHil(faultRun(), hooks);
  EXPECT_FALSE(r.tripped);
  EXPECT_EQ(r.timing.overruns, 5u);
}

TEST(FaultInjection, Estop) {
  RunHooks hooks;
  hooks.before_tick = [](std::uint64_t k, JointSample&, SupervisorRequests& r) {
    if (k == kFaultTick) r.estop_command = true;
  };
  expectLatchedTrip(faultRun(), hooks, SupervisorCause::kEstopCommand);
}

TEST(FaultInjection, LostHeartbeat) {
  RunHooks hooks;
  hooks.before_tick = [](std::uint64_t k, JointSample&, SupervisorRequests& r) {
    if (k >= kFaultTick) r.heartbeat = 49;  // the supervising side stops beating
  };
  expectLatchedTrip(faultRun(), hooks, SupervisorCause::kHeartbeatLost, kFaultTick + 240);
}

TEST(FaultInjection, SearchStalledMidContactFadesTheForcesWithinTheRate) {
  // Start at the wheel, in contact, the user holding there.
  const auto dir = fullarm::test::scratchDir("hil_stall");
  {
    std::ofstream user(dir / "hold.yaml");
    user << "schema_version: 1\nname: hold\narm_impedance: {stiffness_npm: 300.0, damping_nspm: 30.0}\n"
            "push_force_n: 15.0\nhand_path:\n  - {t_s: 0.0, hand_m: [0.101, 0.568, 1.251]}\n";
  }
  RunOptions o = faultRun(2.0);
  o.start_posture = "reach_valve";
  o.user = dir / "hold.yaml";
  const auto maxContact = [](const TickTelemetry& t) {
    double m = 0.0;
    for (int l = 0; l < t.num_config; ++l) m = std::max(m, std::abs(t.tau_contact_nm[static_cast<std::size_t>(l)]));
    return m;
  };
  // Lockstep runs are deterministic: a first run finds a tick in contact after the start-up,
  // the second stalls the search there.
  std::uint64_t stall = 0;
  {
    const RunResult probe = runHil(o);
    for (std::size_t k = 700; k < probe.telemetry.size() && stall == 0; ++k) {
      if (maxContact(probe.telemetry[k]) > 2.0) stall = k + 1;
    }
  }
  ASSERT_GT(stall, 0u) << "the held hand must touch the wheel's surroundings";
  const std::uint64_t kStall = stall;
  RunHooks hooks;
  hooks.search_stalled = [kStall](std::uint64_t k) { return k > kStall; };
  o = logged(o, "stall");
  HilSession session(o);
  const RunResult r = session.run(hooks);
  EXPECT_FALSE(r.tripped) << supervisorCauseName(r.trip_cause);
  const SupervisorParams& p = session.config().supervisor;
  const double max_step = p.max_fade_rate_nm_per_s * 1e-3;
  // In contact when the search stalls.
  const TickTelemetry& before = r.telemetry[kStall - 1];
  ASSERT_GT(maxContact(before), 2.0) << "the arm is in contact when the search stalls";
  bool stale_logged = false;
  for (const SupervisorEvent& e : r.events) {
    if (e.cause == SupervisorCause::kMinimaStale) {
      stale_logged = true;
      EXPECT_GT(e.tick, kStall);
      EXPECT_LE(e.tick, kStall + session.config().delivery_delay_ticks +
                            (p.stale_global_periods + 1) * session.config().global_period_ticks + 1);
    }
  }
  EXPECT_TRUE(stale_logged);
  bool stale_in_log = false;
  for (const fullarm_lcm::supervisor_event_t& e : loggedEvents(o.log)) {
    stale_in_log = stale_in_log || e.cause_code == static_cast<int>(SupervisorCause::kMinimaStale);
    EXPECT_LT(e.severity, static_cast<std::int8_t>(EventSeverity::kFault)) << e.message;
  }
  EXPECT_TRUE(stale_in_log) << "the stale minima are in the LCM log";
  for (std::size_t k = kStall; k < r.telemetry.size(); ++k) {
    for (int l = 0; l < r.telemetry[k].num_config; ++l) {
      const double step = std::abs(r.telemetry[k].tau_contact_nm[l] - r.telemetry[k - 1].tau_contact_nm[l]);
      if (r.telemetry[k].contact_scale < 1.0) {
        ASSERT_LE(step, max_step + 1e-12) << "tick " << k + 1 << " joint " << l;
      }
    }
  }
  const TickTelemetry& last = r.telemetry.back();
  EXPECT_EQ(last.contact_scale, 0.0);
  for (int l = 0; l < last.num_config; ++l) EXPECT_EQ(last.tau_contact_nm[static_cast<std::size_t>(l)], 0.0);
  EXPECT_GT(last.tracked_minima, 0) << "the old minima are still descended";
}

}  // namespace
}  // namespace fullarm::hil
