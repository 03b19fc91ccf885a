// The real-time clock on the simulated DTS: the run keeps the 1 kHz period (timing statistics
// recorded), its LCM log and its recorded inputs replay bit for bit, SIGINT latches an E-stop
// and ends the run, and a real overrun burst trips the supervisor. Timing figures are not
// asserted (they depend on the machine): only that they were measured.

#include <gtest/gtest.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "fullarm/hil/run_recording.hpp"
#include "run_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::hil {
namespace {

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

RunOptions realtimeRun(double duration_s) {
  RunOptions o = test::shippedRun(duration_s);
  o.clock = ClockKind::kRealtime;
  o.oracle = false;
  return o;
}

TEST(Realtime, RunsTheTickOnTheWallClockAndReplaysBitForBit) {
  const auto dir = fullarm::test::scratchDir("hil_realtime");
  RunOptions o = realtimeRun(2.0);
  o.log = dir / "run.lcmlog";
  HilSession session(o);
  const RunResult r = session.run();
  EXPECT_EQ(r.timing.ticks, 2000u);
  EXPECT_GT(r.timing.wall_s, 1.9);
  EXPECT_GT(r.timing.compute.p50_s, 0.0);
  EXPECT_GE(r.timing.period_jitter.max_s, r.timing.period_jitter.p99_s);
  // The per-tick samples behind the statistics (the report's timing histogram).
  ASSERT_EQ(r.timing.compute_samples_s.size(), r.timing.ticks);
  ASSERT_EQ(r.timing.period_jitter_samples_s.size(), r.timing.ticks);
  EXPECT_EQ(percentiles(r.timing.compute_samples_s).p99_s, r.timing.compute.p99_s);
  EXPECT_EQ(percentiles(r.timing.period_jitter_samples_s).max_s, r.timing.period_jitter.max_s);
  EXPECT_GE(r.timing.realtime_notes.size(), 3u);
  EXPECT_GT(r.timing.searches, 100u);
  EXPECT_GT(r.sets.size(), 100u);
  // In memory ...
  const std::vector<TickTelemetry> replayed = session.replay(r);
  ASSERT_EQ(replayed.size(), r.telemetry.size());
  for (std::size_t k = 0; k < replayed.size(); ++k) {
    ASSERT_EQ(replayed[k].valve_v, r.telemetry[k].valve_v) << "tick " << k + 1;
    ASSERT_EQ(replayed[k].tau_contact_nm, r.telemetry[k].tau_contact_nm) << "tick " << k + 1;
  }
  // ... and from the log.
  const ReplayReport report = replayLog(o.log);
  EXPECT_EQ(report.clock, "realtime");
  EXPECT_EQ(report.ticks, r.timing.ticks);
  EXPECT_TRUE(report.identical()) << report.first_mismatch;
}

// The signal's path is the subject here, not the machine's timing: the loop configuration's
// overrun limit is raised so far that a loaded machine (or ThreadSanitizer's slowdown) cannot trip
// the supervisor on overruns before the signal (AnOverrunBurstTripsTheSupervisor tests that trip).
TEST(Realtime, SigintLatchesAnEstopAndEndsTheRun) {
  RunOptions o = realtimeRun(3.0);
  const std::string shipped = readText(o.hil_config);
  const std::string key = "overrun_limit: 10 ";
  const std::size_t at = shipped.find(key);
  ASSERT_NE(at, std::string::npos) << o.hil_config;
  std::string patient = shipped;
  patient.replace(at, key.size(), "overrun_limit: 1000000 ");
  o.hil_config = fullarm::test::scratchDir("hil_realtime_sigint") / "hil.yaml";
  std::ofstream(o.hil_config) << patient;
  RunHooks hooks;
  hooks.before_tick = [](std::uint64_t k, JointSample&, SupervisorRequests&) {
    if (k == 500) std::raise(SIGINT);
  };
  const RunResult r = runHil(o, hooks);
  EXPECT_TRUE(r.tripped);
  EXPECT_EQ(r.trip_cause, SupervisorCause::kEstopSignal);
  EXPECT_LT(r.timing.ticks, 700u) << "the run ends 0.1 s after the signal";
  for (std::size_t k = 501; k < r.telemetry.size(); ++k) {
    for (const double v : r.telemetry[k].valve_v) ASSERT_EQ(v, 0.0);
  }
}

TEST(Realtime, AnOverrunBurstTripsTheSupervisor) {
  RunHooks hooks;
  hooks.extra_compute_s = [](std::uint64_t k) { return k >= 500 && k < 530 ? 1.5e-3 : 0.0; };
  const RunResult r = runHil(realtimeRun(1.0), hooks);
  EXPECT_TRUE(r.tripped);
  EXPECT_EQ(r.trip_cause, SupervisorCause::kOverrun);
  EXPECT_GE(r.timing.overruns, 10u);
  EXPECT_GE(r.timing.max_consecutive_overruns, 10);
}

}  // namespace
}  // namespace fullarm::hil
