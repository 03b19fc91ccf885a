// Remote I/O over LCM udpm, inside a private network namespace the test makes (loopback only:
// nothing can leave the process's own namespace). The plant node serves from a thread with its
// own LCM instances, exactly as it would from another process. A lockstep run over the remote
// device equals the in-process run bit for bit; the plant node's watchdog puts out the safe
// output when commands stop; a read without an answer faults the device, naming readings of
// another message version; chamber pressures travel with the readings.

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <thread>

#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/lcm_search.hpp"
#include "fullarm/hil/node_description.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/run_recording.hpp"
#include "fullarm/hil/sim_io.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "hil_fixture.hpp"
#include "private_network.hpp"
#include "run_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::hil {
namespace {

// A group other than the default, so a stray node elsewhere could not answer even outside the
// namespace.
constexpr const char* kUrl = "udpm://239.255.76.99:7699?ttl=0";

class LcmIo : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string error = test::enterPrivateNetwork();
    ASSERT_EQ(error, "") << "the test needs a private network namespace (unshare) and could not make one";
  }
};

template <std::size_t N>
bool sameBits(const std::array<double, N>& a, const std::array<double, N>& b) {
  return std::memcmp(a.data(), b.data(), sizeof(double) * N) == 0;
}

/// The hand held against the valve wheel: in contact after the start-up.
RunOptions holdAtTheWheel(double duration_s) {
  const auto dir = fullarm::test::scratchDir("hil_lcm_io");
  {
    std::ofstream user(dir / "hold.yaml");
    user << "schema_version: 1\nname: hold\narm_impedance: {stiffness_npm: 300.0, damping_nspm: 30.0}\n"
            "push_force_n: 15.0\nhand_path:\n  - {t_s: 0.0, hand_m: [0.101, 0.568, 1.251]}\n";
  }
  RunOptions o = test::shippedRun(duration_s);
  o.oracle = false;
  o.start_posture = "reach_valve";
  o.user = dir / "hold.yaml";
  return o;
}

/// Forces, torques, valve commands and readings of two runs, bit for bit.
void expectSameRun(const RunResult& in_process, const RunResult& remote) {
  ASSERT_EQ(in_process.telemetry.size(), remote.telemetry.size());
  bool driven = false;
  bool touched = false;
  for (std::size_t k = 0; k < remote.telemetry.size(); ++k) {
    const TickTelemetry& a = in_process.telemetry[k];
    const TickTelemetry& b = remote.telemetry[k];
    ASSERT_EQ(std::memcmp(&a.sample_t_s, &b.sample_t_s, sizeof(double)), 0) << "tick " << k + 1;
    ASSERT_TRUE(sameBits(a.q_rad, b.q_rad)) << "tick " << k + 1;
    ASSERT_TRUE(sameBits(a.tau_load_cell_nm, b.tau_load_cell_nm)) << "tick " << k + 1;
    ASSERT_TRUE(sameBits(a.valve_v, b.valve_v)) << "tick " << k + 1;
    ASSERT_TRUE(sameBits(a.tau_contact_nm, b.tau_contact_nm)) << "tick " << k + 1;
    for (std::size_t l = 0; l < a.link_force_W_n.size(); ++l) {
      ASSERT_TRUE(sameBits(a.link_force_W_n[l], b.link_force_W_n[l])) << "tick " << k + 1 << " link " << l;
    }
    ASSERT_EQ(a.minima_set_id, b.minima_set_id) << "tick " << k + 1;
    for (const double v : a.valve_v) driven = driven || v != 0.0;
    for (const double t : a.tau_contact_nm) touched = touched || t != 0.0;
  }
  EXPECT_TRUE(driven);
  EXPECT_TRUE(touched) << "the scenario should bring the arm into contact";
  EXPECT_EQ(in_process.tripped, remote.tripped);
}

/// A global node serving the search from a thread, built from a run's files.
struct GlobalThread {
  GlobalThread(const RunOptions& options, GlobalNodeOptions node_options)
      : session(options, false),
        search(session.model(), session.world(), session.hapticsParams()),
        node(search, session.model().numJoints(), std::move(node_options)) {
    thread = std::thread([this] { result = node.serve([this] { return stop.load(); }); });
  }
  ~GlobalThread() { join(); }
  void join() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
  /// Waits for the node to stop by itself (idle_exit_s after its last query), so that every
  /// query it received has been answered.
  void joinWhenIdle() {
    if (thread.joinable()) thread.join();
  }
  HilSession session;
  GlobalSearchRunner search;
  LcmGlobalNode node;
  std::atomic<bool> stop{false};
  GlobalNodeResult result;
  std::thread thread;
};

/// `options` saying what the device of `session` serves.
PlantNodeOptions described(HilSession& session, PlantNodeOptions options) {
  options.info = describeSessionDevice(session);
  return options;
}

/// A plant node serving a run's simulated arm (its files and seed) from a thread.
struct SessionPlantThread {
  SessionPlantThread(const RunOptions& options, PlantNodeOptions node_options)
      : session(options), node(session.device(), described(session, std::move(node_options))) {
    thread = std::thread([this] { result = node.serve([this] { return stop.load(); }); });
  }
  ~SessionPlantThread() { join(); }
  void join() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
  /// Waits for the node to stop by itself (idle_exit_s after its last query), so that every
  /// query it received has been answered.
  void joinWhenIdle() {
    if (thread.joinable()) thread.join();
  }
  HilSession session;
  LcmPlantNode node;
  std::atomic<bool> stop{false};
  PlantNodeResult result;
  std::thread thread;
};

PlantNodeOptions plantOptions() {
  PlantNodeOptions o;
  o.url = kUrl;
  o.idle_exit_s = 20.0;
  return o;
}

GlobalNodeOptions globalOptions() {
  GlobalNodeOptions o;
  o.url = kUrl;
  o.idle_exit_s = 20.0;
  o.heartbeat_period_s = 0.01;
  return o;
}

/// `local` over the nodes: remote I/O, and the global node's search if `remote_search`.
RunOptions overTheNodes(RunOptions local, bool remote_search) {
  local.io = IoKind::kLcm;
  local.lcm_url = kUrl;
  if (remote_search) local.search_url = kUrl;
  return local;
}

/// Listens to the plant node's heartbeats on kUrl for up to 2 s; true as soon as one satisfies `done`.
bool waitForPlantHeartbeat(const std::function<bool(const HeartbeatRecord&)>& done) {
  lcm::LCM listen(kUrl);
  LcmReceiverOptions o;
  o.heartbeat = true;
  LcmReceiver rx(listen, o);
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (std::chrono::steady_clock::now() < until) {
    rx.drainWait(0.02);
    const HeartbeatRecord* h = rx.lastHeartbeat(NodeKind::kPlant);
    if (h != nullptr && done(*h)) return true;
  }
  return false;
}

std::vector<std::string> armJointNames();

TEST_F(LcmIo, ARunOverRemoteIoEqualsTheInProcessRunBitForBit) {
  RunOptions local = holdAtTheWheel(1.5);
  const RunResult in_process = runHil(local);

  SessionPlantThread plant(local, plantOptions());  // the same files and seed
  RunOptions over = overTheNodes(local, false);
  over.log = fullarm::test::scratchDir("hil_lcm_io_remote_log") / "run.lcmlog";
  const RunResult remote = runHil(over);
  // The safe output at the end is sent without a reply: the node is stopped once its heartbeat
  // says it served that command (on a loaded machine the node's thread may not have run yet).
  const auto last_command = static_cast<std::int64_t>(remote.telemetry.size() + 1);
  const bool served_last = waitForPlantHeartbeat(
      [last_command](const HeartbeatRecord& h) { return h.tick == last_command && h.safe_output; });
  EXPECT_TRUE(served_last) << "the node's heartbeat never said it served command " << last_command;
  plant.join();

  EXPECT_EQ(remote.io_name, "lcm");
  // One command per tick, and the safe output the device sends when the run deactivates it.
  EXPECT_EQ(plant.result.commands, remote.telemetry.size() + 1);
  EXPECT_TRUE(plant.result.safe_at_exit);
  expectSameRun(in_process, remote);

  // The log's header records what the node said it serves; the log replays bit for bit.
  const ReplayReport replay = replayLog(over.log);
  EXPECT_TRUE(replay.identical()) << replay.first_mismatch;
  std::map<std::string, std::string> node(replay.io_node.begin(), replay.io_node.end());
  std::string joints;
  for (const std::string& n : armJointNames()) joints += (joints.empty() ? "" : ",") + n;
  EXPECT_EQ(node["joints"], joints);
  EXPECT_EQ(node["period_us"], "1000");
  EXPECT_EQ(node["simulated"], "true");
  EXPECT_EQ(node["scripted_user"], "true");  // the node's session straps in the run's user
  const std::filesystem::path plant_file =
      local.plant_config.empty() ? plant::defaultPlantConfigPath() : local.plant_config;
  EXPECT_EQ(node["plant"], plant_file.filename().string() + " sha256 " + sha256File(plant_file));
  EXPECT_EQ(replay.io_node.size(), 5u);
}

TEST_F(LcmIo, ThreeNodesInLockstepEqualTheInProcessRunBitForBit) {
  RunOptions local = holdAtTheWheel(1.5);
  const RunResult in_process = runHil(local);

  SessionPlantThread plant(local, plantOptions());
  GlobalThread global(local, globalOptions());
  const RunResult remote = runHil(overTheNodes(local, true));
  global.join();
  plant.join();
  EXPECT_EQ(global.result.queries, in_process.sets.size());

  ASSERT_EQ(in_process.sets.size(), remote.sets.size());
  for (std::size_t i = 0; i < remote.sets.size(); ++i) {
    EXPECT_EQ(in_process.sets[i].adopted_tick, remote.sets[i].adopted_tick) << "set " << i;
    if (remote.sets[i].adopted_tick < 0) continue;  // queried near the end, never delivered
    EXPECT_EQ(in_process.sets[i].found, remote.sets[i].found) << "set " << i;
    EXPECT_EQ(in_process.sets[i].minima.size(), remote.sets[i].minima.size()) << "set " << i;
  }
  expectSameRun(in_process, remote);
}

TEST_F(LcmIo, TheGlobalNodeStoppedMidContactFadesTheForcesWithinTheRate) {
  RunOptions local = holdAtTheWheel(2.0);
  const auto maxContact = [](const TickTelemetry& t) {
    double m = 0.0;
    for (int l = 0; l < t.num_config; ++l) m = std::max(m, std::abs(t.tau_contact_nm[static_cast<std::size_t>(l)]));
    return m;
  };
  // The in-process run finds a tick in contact after the start-up; the global node stops there.
  std::uint64_t stall = 0;
  {
    const RunResult probe = runHil(local);
    for (std::size_t k = 700; k < probe.telemetry.size() && stall == 0; ++k) {
      if (maxContact(probe.telemetry[k]) > 2.0) stall = k + 1;
    }
  }
  ASSERT_GT(stall, 0u) << "the held hand must touch the wheel's surroundings";

  SessionPlantThread plant(local, plantOptions());
  GlobalThread global(local, globalOptions());
  HilSession session(overTheNodes(local, true));
  RunHooks hooks;
  hooks.before_tick = [&](std::uint64_t k, JointSample&, SupervisorRequests&) {
    if (k == stall) global.join();  // the global node is gone from here on
  };
  const RunResult r = session.run(hooks);
  plant.join();

  EXPECT_FALSE(r.tripped) << supervisorCauseName(r.trip_cause);
  ASSERT_GT(maxContact(r.telemetry[stall - 1]), 2.0) << "in contact when the global node stops";
  const double max_step = session.config().supervisor.max_fade_rate_nm_per_s * session.config().control_period_s;
  for (std::size_t k = stall; k < r.telemetry.size(); ++k) {
    for (int l = 0; l < r.telemetry[k].num_config; ++l) {
      const double step = std::abs(r.telemetry[k].tau_contact_nm[static_cast<std::size_t>(l)] -
                                   r.telemetry[k - 1].tau_contact_nm[static_cast<std::size_t>(l)]);
      if (r.telemetry[k].contact_scale < 1.0) {
        ASSERT_LE(step, max_step + 1e-12) << "tick " << k + 1 << " joint " << l;
      }
    }
  }
  bool stale_logged = false;
  for (const SupervisorEvent& e : r.events) stale_logged = stale_logged || e.cause == SupervisorCause::kMinimaStale;
  EXPECT_TRUE(stale_logged);
  const TickTelemetry& last = r.telemetry.back();
  EXPECT_EQ(last.contact_scale, 0.0);
  for (int l = 0; l < last.num_config; ++l) EXPECT_EQ(last.tau_contact_nm[static_cast<std::size_t>(l)], 0.0);
}

TEST_F(LcmIo, MinimaDelayed50msAreStillAdoptedOnTimeInLockstep) {
  RunOptions local = holdAtTheWheel(1.5);
  const RunResult in_process = runHil(local);
  SessionPlantThread plant(local, plantOptions());
  GlobalNodeOptions go = globalOptions();
  std::atomic<int> delayed{0};
  // One fragment in twenty held back 50 ms on the wire (the publisher thread waits before it).
  go.drop = [&delayed](std::string_view ch, std::int64_t seq) {
    if (ch == channel::kMinimaSet && seq % 20 == 5) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
      ++delayed;
    }
    return false;
  };
  GlobalThread global(local, go);
  const RunResult r = runHil(overTheNodes(local, true));
  global.join();
  plant.join();
  EXPECT_GT(delayed.load(), 3);
  // Lockstep waits for each set at its delivery tick: a late set changes nothing.
  expectSameRun(in_process, r);
}

TEST_F(LcmIo, MinimaFragmentsDroppedAreSetsNotAdoptedAndTheRunStaysSafe) {
  RunOptions local = holdAtTheWheel(1.5);
  SessionPlantThread plant(local, plantOptions());
  GlobalNodeOptions go = globalOptions();
  // One fragment in ten lost, deterministically (a lost fragment loses its set).
  go.drop = [](std::string_view ch, std::int64_t seq) { return ch == channel::kMinimaSet && seq % 10 == 3; };
  GlobalThread global(local, go);
  const RunResult r = runHil(overTheNodes(local, true));
  global.join();
  plant.join();
  std::size_t adopted = 0;
  for (const RecordedSet& s : r.sets) adopted += s.adopted_tick >= 0 ? 1 : 0;
  EXPECT_LT(adopted, r.sets.size()) << "some sets lost a fragment";
  EXPECT_GT(adopted, r.sets.size() * 3 / 4);
  EXPECT_FALSE(r.tripped) << supervisorCauseName(r.trip_cause);
}

// A second run against the same global node restarts the set numbering at 1: the node hears it
// at once (a restarted producer), so the second run is served exactly as the first.
TEST_F(LcmIo, TwoLockstepRunsInARowAreBothServedByOneGlobalNode) {
  RunOptions local = holdAtTheWheel(0.6);
  const RunResult in_process = runHil(local);
  GlobalNodeOptions go = globalOptions();
  // A run's last queries are for sets due after its end, which it does not wait for: the node
  // stops by itself once idle, after answering them, rather than when the second run ends.
  go.idle_exit_s = 1.0;
  GlobalThread global(local, go);
  RunOptions remote = local;
  remote.search_url = kUrl;
  const RunResult first = runHil(remote);
  const RunResult second = runHil(remote);
  global.joinWhenIdle();
  EXPECT_EQ(global.result.queries, 2 * in_process.sets.size());
  EXPECT_EQ(global.result.stale, 0u);
  bool restart_logged = false;
  for (const std::string& line : global.result.log)
    restart_logged = restart_logged || line.find("restarted") != std::string::npos;
  EXPECT_TRUE(restart_logged);
  expectSameRun(in_process, first);
  expectSameRun(in_process, second);
}

// Real time: the tick sends its joint angles live every global period (100 Hz) through the
// publisher thread; the global node answers the newest with a set, and the tick adopts each set
// as it arrives, later than its query.
TEST_F(LcmIo, ARealTimeRunAdoptsTheGlobalNodesSetsLive) {
  RunOptions local = holdAtTheWheel(1.0);
  local.clock = ClockKind::kRealtime;
  GlobalThread global(local, globalOptions());
  RunOptions remote = local;
  remote.search_url = kUrl;
  HilSession session(remote);
  const RunResult r = session.run();
  global.join();

  const auto period_ticks = static_cast<std::uint64_t>(session.config().global_period_ticks);
  const std::uint64_t queries = r.telemetry.size() / period_ticks;
  const double run_s = static_cast<double>(r.telemetry.size()) * session.config().control_period_s;
  ASSERT_GT(queries, 50u);
  // Every query the tick pushed reached the node: >= 100 Hz of live joint states.
  EXPECT_GE(global.result.live_states, queries - 1);
  EXPECT_GE(static_cast<double>(global.result.live_states) / run_s, 0.99 * 100.0 - 1.0 / run_s);
  EXPECT_GT(global.result.live_sets, 0u);
  EXPECT_EQ(global.result.queries, 0u) << "no lockstep query in a real-time run";
  std::uint64_t adopted = 0;
  for (const RecordedSet& s : r.sets) {
    if (s.adopted_tick < 0) continue;
    ++adopted;
    EXPECT_EQ(s.query_tick % period_ticks, 0u);
    EXPECT_GT(static_cast<std::uint64_t>(s.adopted_tick), s.query_tick) << "a set is adopted after its query";
  }
  EXPECT_GT(adopted, queries / 2) << "most sets arrive before the next one";
  bool touched = false;
  for (const TickTelemetry& t : r.telemetry) {
    for (const double tau : t.tau_contact_nm) touched = touched || tau != 0.0;
  }
  EXPECT_TRUE(touched) << "the scenario should bring the arm into contact";
}

// The global node stops mid-contact in a real-time run: its sets stop, the contact forces fade
// at their rate, and when its heartbeat has been missing for peer_heartbeat_timeout_s the
// supervisor trips with communication lost: every valve at null, the cause in the log, and the
// log replays bit for bit.
TEST_F(LcmIo, ALostGlobalNodeHeartbeatInRealTimeIsCommunicationLossAfterTheFade) {
  RunOptions local = holdAtTheWheel(1.6);
  local.clock = ClockKind::kRealtime;
  local.log = fullarm::test::scratchDir("hil_lcm_io_peer") / "run.lcmlog";
  GlobalThread global(local, globalOptions());
  RunOptions remote = local;
  remote.search_url = kUrl;
  HilSession session(remote);
  const std::uint64_t stop_tick = 700;
  RunHooks hooks;
  hooks.before_tick = [&](std::uint64_t k, JointSample&, SupervisorRequests&) {
    if (k == stop_tick) global.stop = true;  // the node stops serving: no set, no heartbeat
  };
  const RunResult r = session.run(hooks);
  global.join();

  ASSERT_TRUE(r.tripped);
  EXPECT_EQ(r.trip_cause, SupervisorCause::kPeerHeartbeatLost) << supervisorCauseName(r.trip_cause);
  const SupervisorEvent* trip = nullptr;
  for (const SupervisorEvent& e : r.events) {
    if (e.trip && trip == nullptr) trip = &e;
  }
  ASSERT_NE(trip, nullptr);
  const double dt = session.config().control_period_s;
  const double timeout_s = session.config().supervisor.peer_heartbeat_timeout_s;
  // The node's last heartbeat is at most one heartbeat period before it stopped, or earlier when
  // its thread waited for a core; the watcher and the tick add a few milliseconds. The ticks
  // count wall time only while the loop keeps its period, which a loaded 2-core machine can
  // break for a few milliseconds: the lower bound allows for that, and a trip well before the
  // timeout still fails.
  const double silent_s = static_cast<double>(trip->tick - stop_tick) * dt;
  const double scheduling_slack_s = 0.05;
  EXPECT_GE(silent_s, timeout_s - globalOptions().heartbeat_period_s - scheduling_slack_s);
  EXPECT_LE(silent_s, timeout_s + 0.2);
  // Before the trip the contact forces faded at their rate (once stale) and were gone.
  const double max_step = session.config().supervisor.max_fade_rate_nm_per_s * dt;
  const TickTelemetry& before = r.telemetry[trip->tick - 2];
  EXPECT_EQ(before.contact_scale, 0.0);
  for (std::size_t k = stop_tick; k + 1 < trip->tick; ++k) {
    if (r.telemetry[k].contact_scale == 1.0) continue;  // not fading yet: the minima are fresh enough
    for (int j = 0; j < r.telemetry[k].num_config; ++j) {
      const auto i = static_cast<std::size_t>(j);
      EXPECT_LE(std::abs(r.telemetry[k].tau_contact_nm[i] - r.telemetry[k - 1].tau_contact_nm[i]), max_step + 1e-12)
          << "tick " << k + 1;
    }
  }
  // From the trip on, the safe outputs: every valve at null.
  for (std::size_t k = trip->tick - 1; k < r.telemetry.size(); ++k) {
    for (const double v : r.telemetry[k].valve_v) ASSERT_EQ(v, 0.0) << "tick " << k + 1;
  }
  const ReplayReport replay = replayLog(local.log);
  EXPECT_TRUE(replay.identical()) << replay.first_mismatch;
}

/// The names of test::armJoints(), in order.
std::vector<std::string> armJointNames() {
  std::vector<std::string> names;
  for (int k = 0; k < test::armJoints().size(); ++k) {
    names.push_back(test::model().joints[static_cast<std::size_t>(test::armJoints().modelIndex(k))].name);
  }
  return names;
}

/// `options` saying that the node serves test::armJoints() (unless it names joints already).
PlantNodeOptions withArmJoints(PlantNodeOptions options) {
  if (options.info.joint_names.empty()) options.info.joint_names = armJointNames();
  return options;
}

/// A plant node serving a simulated arm from a thread.
struct PlantThread {
  explicit PlantThread(PlantNodeOptions options, const plant::PlantConfig& plant = test::plantConfig())
      : arm(std::make_unique<SimulatedArm>(test::model(), plant, test::restPosture(), 1e-3, 1)),
        device(*arm, SimIoOptions{}, IoSafetyParams{}),
        node(device, withArmJoints(options)) {
    thread = std::thread([this] { result = node.serve([this] { return stop.load(); }); });
  }
  ~PlantThread() { join(); }
  void join() {
    stop = true;
    if (thread.joinable()) thread.join();
  }
  /// Waits for the node to stop by itself (idle_exit_s after its last query), so that every
  /// query it received has been answered.
  void joinWhenIdle() {
    if (thread.joinable()) thread.join();
  }
  std::unique_ptr<SimulatedArm> arm;
  SimIoDevice device;
  LcmPlantNode node;
  std::atomic<bool> stop{false};
  PlantNodeResult result;
  std::thread thread;
};

LcmIoOptions deviceOptions() {
  LcmIoOptions o;
  o.url = kUrl;
  o.joint_names = armJointNames();
  o.connect_timeout_s = 5.0;
  o.reply_timeout_s = 0.2;
  return o;
}

TEST_F(LcmIo, ThePlantNodesWatchdogPutsOutTheSafeOutputWhenCommandsStop) {
  PlantNodeOptions po;
  po.url = kUrl;
  po.watchdog_timeout_s = 0.05;
  po.idle_exit_s = 0.4;
  po.heartbeat_period_s = 0.01;
  PlantThread plant(po);
  {
    LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{0.0, 10.0}, deviceOptions());
    device.configure();
    device.activate();
    JointSample s;
    const IoVector command = IoVector::Constant(device.numJoints(), 2.0);
    for (int k = 0; k < 20; ++k) {
      ASSERT_TRUE(device.read(s).ok());
      ASSERT_TRUE(device.write(command).ok());
    }
    ASSERT_TRUE(device.read(s).ok());  // the plant now holds 2 V on every valve
    // The tick goes silent (its process died): no further command.
  }
  // Heartbeats after the silence say the plant holds its safe outputs.
  lcm::LCM listen(kUrl);
  LcmReceiver rx(listen, [] {
    LcmReceiverOptions o;
    o.heartbeat = true;
    return o;
  }());
  const auto until = std::chrono::steady_clock::now() + std::chrono::milliseconds(200);
  while (std::chrono::steady_clock::now() < until) rx.drainWait(0.02);
  plant.thread.join();  // the node stops after idle_exit_s
  EXPECT_EQ(plant.result.commands, 21u);
  EXPECT_EQ(plant.result.watchdog_trips, 1u);
  EXPECT_TRUE(plant.result.safe_at_exit);
  bool logged = false;
  for (const std::string& line : plant.result.log) logged = logged || line.find("watchdog") != std::string::npos;
  EXPECT_TRUE(logged);
  const HeartbeatRecord* h = rx.lastHeartbeat(NodeKind::kPlant);
  ASSERT_NE(h, nullptr);
  EXPECT_TRUE(h->safe_output);
  EXPECT_EQ(h->tick, 21);
}

TEST_F(LcmIo, ConsecutiveReadsWithoutAnAnswerFaultTheDevice) {
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  auto plant = std::make_unique<PlantThread>(po);
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, deviceOptions());
  device.configure();
  device.activate();
  JointSample s;
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(device.read(s).ok());
  const JointSample last = s;
  plant->join();  // the plant node is gone
  const int n = LcmIoOptions{}.max_missed_replies;
  for (int k = 1; k < n; ++k) {
    ASSERT_TRUE(device.read(s).ok()) << "miss " << k << " of " << n << " holds the last reading";
    EXPECT_EQ(s.q_rad, last.q_rad);
    EXPECT_EQ(s.t_s, last.t_s);
    EXPECT_EQ(device.state(), IoState::kActive);
  }
  const core::RtStatus status = device.read(s);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.faults & kFaultDeviceRead, 0u);
  EXPECT_NE(status.faults & kFaultLinkLost, 0u);
  EXPECT_EQ(device.state(), IoState::kFault);
  EXPECT_EQ(device.counters().timeouts, static_cast<std::uint64_t>(n));
  EXPECT_EQ(device.counters().readings, 5u);
}

// A plant whose elbow has chamber pressure transducers: the remote device's readings carry the
// pressures, bit for bit as the same plant's in-process sim device reads them, and only the
// elbow's bit in the mask.
TEST_F(LcmIo, ChamberPressuresTravelWithTheReadings) {
  const plant::PlantConfig plant_config = test::plantWithElbowTransducers();
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  PlantThread plant(po, plant_config);
  LcmIoDevice remote(test::armJoints(), 1e-3, IoSafetyParams{}, deviceOptions());
  remote.configure();
  SimulatedArm arm(test::model(), plant_config, test::restPosture(), 1e-3, 1);
  SimIoDevice in_process(arm, SimIoOptions{}, IoSafetyParams{});
  in_process.configure();
  JointSample a;
  JointSample b;
  for (int k = 0; k < 30; ++k) {
    ASSERT_TRUE(remote.read(a).ok()) << k;
    ASSERT_TRUE(in_process.read(b).ok()) << k;
    ASSERT_EQ(a.pressure_mask, 1u << 3) << k;
    ASSERT_EQ(b.pressure_mask, 1u << 3) << k;
    EXPECT_EQ(a.q_rad, b.q_rad) << k;
    EXPECT_EQ(a.p_a_pa, b.p_a_pa) << k;
    EXPECT_EQ(a.p_b_pa, b.p_b_pa) << k;
  }
  EXPECT_GT(a.p_a_pa[3], 0.0);
  EXPECT_GT(a.p_b_pa[3], 0.0);
}

/// The message of configure() on `device`, or "" when it succeeded.
std::string configureError(LcmIoDevice& device) {
  try {
    device.configure();
  } catch (const DeviceError& e) {
    return e.what();
  }
  return "";
}

TEST_F(LcmIo, TheDeviceReceivesWhatTheNodeSaysItServes) {
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  po.info.scripted_user = true;
  po.info.plant = "dts_plant.yaml sha256 0123abcd";
  PlantThread plant(po);
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, deviceOptions());
  EXPECT_EQ(device.nodeInfo(), nullptr) << "nothing heard before configure()";
  ASSERT_EQ(configureError(device), "");
  const IoNodeInfo* info = device.nodeInfo();
  ASSERT_NE(info, nullptr);
  EXPECT_EQ(info->joint_names, armJointNames());
  EXPECT_EQ(info->period_us, 1000) << "the node states its device's period";
  EXPECT_TRUE(info->simulated);
  EXPECT_TRUE(info->scripted_user);
  EXPECT_EQ(info->plant, "dts_plant.yaml sha256 0123abcd");
  EXPECT_EQ(device.counters().rejected, 0u);
}

TEST_F(LcmIo, ConfiguringAgainstANodeServingOtherJointsNamesTheMismatch) {
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  po.info.joint_names = armJointNames();
  std::swap(po.info.joint_names[1], po.info.joint_names[2]);  // the same joints in another order
  PlantThread plant(po);
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, deviceOptions());
  const std::string error = configureError(device);
  const std::vector<std::string> names = armJointNames();
  std::string expected;
  for (const std::string& n : names) expected += (expected.empty() ? "" : ",") + n;
  EXPECT_NE(error.find("the node at " + std::string(kUrl) + " serves joints " + names[0] + "," + names[2] + "," +
                       names[1] + ","),
            std::string::npos)
      << error;
  EXPECT_NE(error.find("; expected " + expected + " every 1000 us"), std::string::npos) << error;
  EXPECT_EQ(device.nodeInfo(), nullptr);
}

TEST_F(LcmIo, ConfiguringAgainstANodeOfAnotherPeriodNamesTheMismatch) {
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  PlantThread plant(po);  // a simulated arm stepped every 1 ms
  LcmIoDevice device(test::armJoints(), 2e-3, IoSafetyParams{}, deviceOptions());
  const std::string error = configureError(device);
  EXPECT_NE(error.find("the node at " + std::string(kUrl) + " serves joints"), std::string::npos) << error;
  EXPECT_NE(error.find(" every 1000 us; expected "), std::string::npos) << error;
  EXPECT_NE(error.find(" every 2000 us"), std::string::npos) << error;
}

TEST_F(LcmIo, ASessionsDeviceIsDescribedByItsFilesAndUser) {
  RunOptions local = test::shippedRun(0.1);
  local.scripted_user = false;
  HilSession session(local);
  const IoNodeInfo info = describeSessionDevice(session);
  ASSERT_EQ(static_cast<int>(info.joint_names.size()), session.device().numJoints());
  for (int k = 0; k < session.device().numJoints(); ++k) {
    EXPECT_EQ(info.joint_names[static_cast<std::size_t>(k)],
              session.model().joints[static_cast<std::size_t>(session.device().joints().modelIndex(k))].name);
  }
  EXPECT_EQ(info.period_us, std::lround(session.config().control_period_s * 1e6));
  EXPECT_TRUE(info.simulated);
  EXPECT_FALSE(info.scripted_user);
  const std::filesystem::path plant = session.options().plant_config;
  EXPECT_EQ(info.plant, plant.filename().string() + " sha256 " + sha256File(plant));
  HilSession with_user(test::shippedRun(0.1));
  EXPECT_TRUE(describeSessionDevice(with_user).scripted_user);

  // A plant file whose name is not ASCII: the name travels with '?' for each other byte, the hash
  // unchanged, and the description is one the tick side's decoder accepts.
  const auto renamed = fullarm::test::scratchDir("hil_lcm_io_names") / "pl\xC3\xA4nt.yaml";
  std::filesystem::copy_file(plant, renamed, std::filesystem::copy_options::overwrite_existing);
  RunOptions other = test::shippedRun(0.1);
  other.scripted_user = false;
  other.plant_config = renamed;
  HilSession session_renamed(other);
  const IoNodeInfo described = describeSessionDevice(session_renamed);
  EXPECT_EQ(described.plant, "pl??nt.yaml sha256 " + sha256File(plant));
  std::vector<std::uint8_t> bytes;
  encodeMessage(toMessage(described), bytes);
  fullarm_lcm::io_node_info_t decoded{};
  EXPECT_EQ(decodeChecked(bytes, decoded), DecodeStatus::kOk);
}

// A node whose description the tick side's decoder would drop (a joint name longer than the
// protocol carries) refuses to serve, naming the bounds, rather than leave the tick to time out.
TEST_F(LcmIo, ANodeRefusesADescriptionTheProtocolCannotCarry) {
  std::unique_ptr<SimulatedArm> arm = test::makeArm(1);
  SimIoDevice device(*arm, SimIoOptions{}, IoSafetyParams{});
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 0.1;
  po.info.joint_names = armJointNames();
  po.info.joint_names[3] = std::string(kMaxNodeJointNameChars + 1, 'J');
  LcmPlantNode node(device, po);
  try {
    (void)node.serve([] { return false; });
    ADD_FAILURE() << "served";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("joint names of 1 to " + std::to_string(kMaxNodeJointNameChars)),
              std::string::npos)
        << e.what();
  }
}

// Heartbeats but no description (a node of an older protocol): the device error names the URL and
// the description's channel once the connection time is up.
TEST_F(LcmIo, ANodeThatNeverDescribesItselfIsADeviceErrorNamingTheChannel) {
  // Heartbeats from a publisher of the test (a node of this version always describes itself).
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  std::atomic<bool> stop{false};
  std::thread beats([&] {
    fullarm_lcm::heartbeat_t beat{};
    beat.node = 0;
    std::vector<std::uint8_t> bytes;
    while (!stop) {
      ++beat.seq;
      encodeMessage(beat, bytes);
      lcm.publish(channel::kHeartbeat, bytes.data(), static_cast<unsigned int>(bytes.size()));
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
  });
  LcmIoOptions o = deviceOptions();
  o.connect_timeout_s = 0.3;
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, o);
  const std::string error = configureError(device);
  stop = true;
  beats.join();
  EXPECT_NE(error.find("the node at " + std::string(kUrl) + " did not say what it serves within 0.3 s"),
            std::string::npos)
      << error;
  EXPECT_NE(error.find(channel::kIoNodeInfo), std::string::npos) << error;
}

// A node restarted at the same URL under another description (here another plant file) while the
// device runs: its readings carry another description id, and the device faults at the first one
// rather than take readings of another plant.
TEST_F(LcmIo, ANodeRestartedUnderAnotherDescriptionFaultsTheDevice) {
  PlantNodeOptions first;
  first.url = kUrl;
  first.idle_exit_s = 5.0;
  first.info.plant = "dts_plant.yaml sha256 0123";
  auto plant = std::make_unique<PlantThread>(first);
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, deviceOptions());
  device.configure();
  EXPECT_EQ(device.acceptedDescriptionId(), descriptionId(*device.nodeInfo()));
  EXPECT_NE(device.acceptedDescriptionId(), 0);
  device.activate();
  JointSample s;
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(device.read(s).ok());
  plant->join();
  PlantNodeOptions second = first;
  second.info.plant = "other_plant.yaml sha256 4567";
  plant = std::make_unique<PlantThread>(second);
  // Wait until the new node listens (it beats): a read sent before would find nobody and count as a
  // missed reply, which is another fault.
  {
    lcm::LCM listen(kUrl);
    ASSERT_TRUE(listen.good());
    struct Beats {
      int count = 0;
      void onBeat(const lcm::ReceiveBuffer*, const std::string&) { ++count; }
    } beats;
    listen.subscribe(channel::kHeartbeat, &Beats::onBeat, &beats);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (beats.count < 2 && std::chrono::steady_clock::now() < deadline) listen.handleTimeout(100);
    ASSERT_GE(beats.count, 2) << "the second node did not start";
  }
  const core::RtStatus status = device.read(s);
  ASSERT_FALSE(status.ok());
  EXPECT_NE(status.faults & kFaultDeviceRead, 0u);
  EXPECT_NE(std::string(status.message).find("another description"), std::string::npos) << status.message;
  EXPECT_EQ(device.state(), IoState::kFault);
  // The ids differ for any field of the description, and not for the sequence or time.
  IoNodeInfo a = *device.nodeInfo();
  IoNodeInfo b = a;
  EXPECT_EQ(descriptionId(a), descriptionId(b));
  b.scripted_user = !a.scripted_user;
  EXPECT_NE(descriptionId(a), descriptionId(b));
  b = a;
  b.period_us += 1;
  EXPECT_NE(descriptionId(a), descriptionId(b));
}

// A node of another version answers every command with a reading the device cannot decode (its
// type hash differs): the read fails naming the likely cause, not as a plain lost link.
TEST_F(LcmIo, ReadingsOfAnotherMessageVersionAreNamedAsSuch) {
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  auto plant = std::make_unique<PlantThread>(po);
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, deviceOptions());
  device.configure();
  plant->join();
  lcm::LCM lcm(kUrl);
  ASSERT_TRUE(lcm.good());
  struct OldNode {
    lcm::LCM* lcm;
    int answered = 0;
    void onCommand(const lcm::ReceiveBuffer* rbuf, const std::string&) {
      fullarm_lcm::io_command_t command{};
      if (command.decode(rbuf->data, 0, static_cast<int>(rbuf->data_size)) < 0) return;
      fullarm_lcm::io_reading_t reading{};
      reading.seq = command.seq;
      reading.num_joints = 7;
      reading.q_rad.assign(7, 0.5);
      reading.tau_load_cell_nm.assign(7, 0.0);
      reading.p_a_pa.assign(7, 0.0);
      reading.p_b_pa.assign(7, 0.0);
      std::vector<std::uint8_t> bytes;
      encodeMessage(reading, bytes);
      bytes[7] ^= 0x5A;  // the type hash of another layout
      lcm->publish(channel::kIoReading, bytes.data(), static_cast<unsigned int>(bytes.size()));
      ++answered;
    }
  } old_node{&lcm};
  lcm.subscribe(channel::kIoCommand, &OldNode::onCommand, &old_node);
  std::atomic<bool> stop{false};
  std::thread serve([&] {
    while (!stop) lcm.handleTimeout(10);
  });
  JointSample s;
  const core::RtStatus status = device.read(s);
  stop = true;
  serve.join();
  ASSERT_FALSE(status.ok());
  EXPECT_GE(old_node.answered, 1);
  EXPECT_GE(device.counters().rejected, 1u);
  EXPECT_NE(status.faults & kFaultLinkLost, 0u);
  EXPECT_NE(std::string(status.message).find("another message version"), std::string::npos) << status.message;
}

TEST_F(LcmIo, ConfiguringWithoutAPlantNodeIsADeviceError) {
  LcmIoOptions o = deviceOptions();
  o.connect_timeout_s = 0.2;
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, o);
  EXPECT_THROW(device.configure(), DeviceError);
}

}  // namespace
}  // namespace fullarm::hil
