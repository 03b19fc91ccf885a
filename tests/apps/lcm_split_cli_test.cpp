// `fullarm plant serve`, `fullarm global`, `fullarm run --io lcm` and `fullarm local` as separate
// processes over LCM udpm, inside a private network namespace the test makes (loopback only). A
// lockstep run over the plant node, and the local node over the plant and global nodes, write the
// in-process run's log bit for bit (every event but the header, which names the I/O back-end);
// in real time the three processes' contact forces agree with the in-process run's within a
// bound derived from the measured latency; killing the plant node faults the run (communication
// lost, supervisor trip, exit 1); killing the run makes the plant node's watchdog put out the
// safe outputs. `fullarm identify` and `fullarm gravity` run their experiments on a plant node
// with nobody strapped in (`--io lcm`, `plant serve --no-user`).

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <limits>
#include <random>
#include <sstream>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "arm_test_util.hpp"
#include "cli_runner.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/node_description.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/run_log.hpp"
#include "fullarm/hil/run_recording.hpp"
#include "fullarm/identification/signal_csv.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "private_network.hpp"
#include "run_replay3d.hpp"

namespace fullarm::app {
namespace {

constexpr const char* kUrl = "udpm://239.255.76.98:7698?ttl=0";

/// A `fullarm` process started in the background, its output in a file.
class Process {
 public:
  Process(const std::vector<std::string>& args, const std::filesystem::path& output) : output_(output) {
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> argv;
      std::string exe = FULLARM_EXE;
      argv.push_back(exe.data());
      std::vector<std::string> copy = args;
      for (std::string& a : copy) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(exe.c_str(), argv.data());
      ::_exit(127);
    }
  }
  ~Process() {
    if (pid_ > 0 && !waited_) {
      ::kill(pid_, SIGKILL);
      (void)wait();
    }
  }
  /// Waits for the process; its exit code, or -signal.
  int wait() {
    int status = 0;
    ::waitpid(pid_, &status, 0);
    waited_ = true;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  }
  void kill() { ::kill(pid_, SIGKILL); }
  /// SIGTERM: a node stops serving and prints its last line.
  void terminate() { ::kill(pid_, SIGTERM); }
  [[nodiscard]] std::string output() const {
    std::ifstream in(output_);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
  }
  /// Waits up to `timeout_s` for `text` in the output.
  bool waitForOutput(const std::string& text, double timeout_s) const {
    const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
    while (std::chrono::steady_clock::now() < until) {
      if (output().find(text) != std::string::npos) return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return false;
  }

 private:
  pid_t pid_ = -1;
  bool waited_ = false;
  std::filesystem::path output_;
};

class LcmSplitCli : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string error = hil::test::enterPrivateNetwork();
    ASSERT_EQ(error, "") << "the test needs a private network namespace (unshare) and could not make one";
    dir_ = test::cliTempDir("lcm_split", ::testing::UnitTest::GetInstance()->current_test_info()->name());
    // The hand held against the valve wheel: in contact after the start-up.
    std::ofstream user(dir_ / "hold.yaml");
    user << "schema_version: 1\nname: hold\narm_impedance: {stiffness_npm: 300.0, damping_nspm: 30.0}\n"
            "push_force_n: 15.0\nhand_path:\n  - {t_s: 0.0, hand_m: [0.101, 0.568, 1.251]}\n";
  }
  [[nodiscard]] std::string scenario() const {
    return "--user " + (dir_ / "hold.yaml").string() + " --start-posture reach_valve --seed 3";
  }
  [[nodiscard]] std::vector<std::string> plantArgs(const std::string& idle_exit) const {
    return {
        "--quiet",         "plant",       "serve",  "--lcm-url", kUrl,         "--user", (dir_ / "hold.yaml").string(),
        "--start-posture", "reach_valve", "--seed", "3",         "--watchdog", "0.05",   "--idle-exit",
        idle_exit};
  }
  std::filesystem::path dir_;
};

/// Every event of a run log but its header: (channel, payload) in order.
std::vector<std::pair<std::string, std::vector<std::uint8_t>>> eventsAfterHeader(const std::filesystem::path& log) {
  std::vector<std::pair<std::string, std::vector<std::uint8_t>>> out;
  hil::LcmLogReader reader(log);
  hil::LcmLogEvent e;
  while (reader.next(e)) {
    if (e.channel == hil::channel::kRunHeader) continue;
    out.emplace_back(e.channel, e.data);
  }
  return out;
}

TEST_F(LcmSplitCli, ALockstepRunOverThePlantNodeWritesTheInProcessRunsLog) {
  Process plant(plantArgs("5"), dir_ / "plant.txt");
  const test::CliResult remote = test::runFullarm("--quiet run --io lcm --lcm-url '" + std::string(kUrl) +
                                                  "' --clock lockstep --duration 1.5 --no-oracle " + scenario() +
                                                  " --out " + (dir_ / "lcm").string());
  ASSERT_EQ(remote.exit_code, 0) << remote.output;
  const test::CliResult local = test::runFullarm("--quiet run --io sim --clock lockstep --duration 1.5 --no-oracle " +
                                                 scenario() + " --out " + (dir_ / "sim").string());
  ASSERT_EQ(local.exit_code, 0) << local.output;
  plant.kill();
  (void)plant.wait();
  EXPECT_NE(plant.output().find("first command"), std::string::npos) << plant.output();

  const auto a = eventsAfterHeader(dir_ / "sim" / "run.lcmlog");
  const auto b = eventsAfterHeader(dir_ / "lcm" / "run.lcmlog");
  ASSERT_GT(a.size(), 1500u);  // joint state, valve command and haptic status per tick at least
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first, b[i].first) << "event " << i;
    ASSERT_TRUE(a[i].second == b[i].second) << "event " << i << " on " << a[i].first << " differs";
  }

  // The header records the node the run was served by; `fullarm replay` names it (and names no
  // node for the in-process run).
  const test::CliResult replay = test::runFullarm("--quiet replay " + (dir_ / "lcm" / "run.lcmlog").string() +
                                                  " --out " + (dir_ / "replay").string());
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("recorded over LCM on a node that said it serves:"), std::string::npos) << replay.output;
  std::ifstream in(dir_ / "replay" / "summary.json");
  const nlohmann::json node = nlohmann::json::parse(in)["results"]["replay"]["io_node"];
  const std::filesystem::path plant_file = plant::defaultPlantConfigPath();
  EXPECT_EQ(node.value("plant", ""), plant_file.filename().string() + " sha256 " + hil::sha256File(plant_file))
      << node.dump();
  EXPECT_EQ(node.value("simulated", ""), "true") << node.dump();
  EXPECT_EQ(node.value("scripted_user", ""), "true") << node.dump();
  EXPECT_EQ(node.value("period_us", ""), "1000") << node.dump();
  EXPECT_NE(node.value("joints", "").find("R_EB"), std::string::npos) << node.dump();
  const test::CliResult replay_sim = test::runFullarm("--quiet replay " + (dir_ / "sim" / "run.lcmlog").string());
  ASSERT_EQ(replay_sim.exit_code, 0) << replay_sim.output;
  EXPECT_EQ(replay_sim.output.find("recorded over LCM"), std::string::npos) << replay_sim.output;
}

TEST_F(LcmSplitCli, ThreeProcessesInLockstepWriteTheInProcessRunsLog) {
  Process plant(plantArgs("5"), dir_ / "plant.txt");
  Process global({"--quiet", "global", "--lcm-url", kUrl, "--idle-exit", "5"}, dir_ / "global.txt");
  // The local node: `fullarm local` (the run with the global node's search, remote I/O by default).
  const test::CliResult remote = test::runFullarm("--quiet local --lcm-url '" + std::string(kUrl) +
                                                  "' --clock lockstep --duration 1.5 --no-oracle " + scenario() +
                                                  " --out " + (dir_ / "lcm").string());
  ASSERT_EQ(remote.exit_code, 0) << remote.output;
  const test::CliResult local = test::runFullarm("--quiet run --io sim --clock lockstep --duration 1.5 --no-oracle " +
                                                 scenario() + " --out " + (dir_ / "sim").string());
  ASSERT_EQ(local.exit_code, 0) << local.output;
  plant.kill();
  global.kill();
  (void)plant.wait();
  (void)global.wait();
  EXPECT_NE(global.output().find("first query"), std::string::npos) << global.output();

  const auto a = eventsAfterHeader(dir_ / "sim" / "run.lcmlog");
  const auto b = eventsAfterHeader(dir_ / "lcm" / "run.lcmlog");
  ASSERT_GT(a.size(), 1500u);
  ASSERT_EQ(a.size(), b.size());
  std::size_t sets = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].first, b[i].first) << "event " << i;
    ASSERT_TRUE(a[i].second == b[i].second) << "event " << i << " on " << a[i].first << " differs";
    sets += a[i].first == hil::channel::kMinimaSet ? 1 : 0;
  }
  EXPECT_GT(sets, 100u) << "the adopted minima sets are in both logs";
}

/// p-quantile of `v` (nearest rank).
double quantile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const auto k = static_cast<std::size_t>(std::ceil(p * static_cast<double>(v.size())));
  return v[std::min(v.size() - 1, k == 0 ? 0 : k - 1)];
}

TEST_F(LcmSplitCli, ThreeProcessesInRealTimeAgreeWithTheInProcessRunWithinTheLatencyBound) {
  const double duration_s = 2.0;
  // In real time the local node waits at most 0.6 ms for each reading and trips with
  // `communication lost` after 20 late ones in a row: a stall of the plant process beyond 20 ms
  // (the test machine is shared) ends the run safely, as it should (KillingThePlantNodeFaultsTheRun
  // tests that outcome). The agreement is measured on a run that was not cut short: up to three
  // attempts, each with fresh nodes; any other failure fails at once.
  std::string global_output;
  test::CliResult remote;
  for (int attempt = 0; attempt < 3; ++attempt) {
    Process plant(plantArgs("5"), dir_ / "plant.txt");
    Process global({"--quiet", "global", "--lcm-url", kUrl, "--idle-exit", "5"}, dir_ / "global.txt");
    remote = test::runFullarm("--quiet local --lcm-url '" + std::string(kUrl) + "' --clock realtime --duration 2 " +
                              scenario() + " --out " + (dir_ / "lcm").string());
    plant.kill();
    global.terminate();
    (void)plant.wait();
    EXPECT_EQ(global.wait(), 0);
    global_output = global.output();
    if (remote.exit_code == 0) break;
    ASSERT_NE(remote.output.find("TRIPPED (communication lost)"), std::string::npos) << remote.output << "\nplant:\n"
                                                                                     << plant.output() << "\nglobal:\n"
                                                                                     << global_output;
    std::cout << "attempt " << attempt + 1 << ": the plant node's readings came late 20 times in a row (a loaded "
              << "machine): the run tripped safely; again\n";
  }
  ASSERT_EQ(remote.exit_code, 0) << remote.output;
  const test::CliResult local = test::runFullarm("--quiet run --io sim --clock lockstep --duration 2 --no-oracle " +
                                                 scenario() + " --out " + (dir_ / "sim").string());
  ASSERT_EQ(local.exit_code, 0) << local.output;
  EXPECT_NE(global_output.find("first live joint state"), std::string::npos) << global_output;
  // The local node sent its joint angles live every global period: >= 100 Hz.
  const std::string& out = global_output;
  const std::size_t at = out.find(" live joint states");
  ASSERT_NE(at, std::string::npos) << out;
  const std::size_t from = out.rfind(' ', at - 1) + 1;
  const double live_states = std::stod(out.substr(from, at - from));
  EXPECT_GE(live_states / duration_s, 100.0 - 1.0 / duration_s) << out;

  hil::RunOptions options;
  options.user = dir_ / "hold.yaml";
  options.start_posture = "reach_valve";
  const hil::HilSession session(options, false);
  const double dt = session.config().control_period_s;
  const hil::RunResult in_process = runFromLog(dir_ / "sim" / "run.lcmlog", session);
  const hil::RunResult split = runFromLog(dir_ / "lcm" / "run.lcmlog", session);
  ASSERT_GE(split.telemetry.size(), static_cast<std::size_t>(0.99 * duration_s / dt));
  ASSERT_EQ(in_process.telemetry.size(), static_cast<std::size_t>(std::llround(duration_s / dt)));

  // The latency of the minima: from the tick whose joint angles went out to the tick that
  // adopted the set (publisher thread, network, search, fragments, the next tick), p99.
  std::vector<double> age_s;
  for (const hil::RecordedSet& s : split.sets) {
    if (s.adopted_tick <= 0) continue;
    age_s.push_back(static_cast<double>(s.adopted_tick - static_cast<std::int64_t>(s.query_tick)) * dt);
  }
  ASSERT_GT(age_s.size(), static_cast<std::size_t>(0.5 * duration_s / (dt * session.config().global_period_ticks)));
  const double latency_p99_s = quantile(age_s, 0.99);
  // The hand's speed, from the run's own joint readings over 20 ms windows (the potentiometers'
  // 12-bit steps would dominate a one-tick difference).
  arm::ArmData fk(session.model());
  std::vector<Eigen::Vector3d> hand;
  for (const hil::TickTelemetry& t : split.telemetry) {
    Eigen::VectorXd q = Eigen::VectorXd::Zero(session.model().numJoints());
    for (int j = 0; j < t.num_device_joints; ++j)
      q[session.tickModel().device_joints.modelIndex(j)] = t.q_rad[static_cast<std::size_t>(j)];
    arm::computeForwardKinematics(session.model(), fk, q);
    hand.push_back(fk.X_WT.translation());
  }
  const std::size_t window = 20;
  double hand_speed_mps = 0.0;
  for (std::size_t k = window; k < hand.size(); ++k)
    hand_speed_mps = std::max(hand_speed_mps, (hand[k] - hand[k - window]).norm() / (static_cast<double>(window) * dt));
  // Tolerance: a spring's force changes by at most k * (change of its distance); between the two
  // runs a link's minima differ by the set's age, at most the measured p99 latency plus one
  // search period here against the configured delivery delay there, travelled at the hand's
  // largest speed.
  const double stiffness_npm = session.hapticsParams().stiffness_npm;
  const double search_period_s = session.config().global_period_ticks * dt;
  const double lockstep_delay_s = session.config().delivery_delay_ticks * dt;
  const double tolerance_n = stiffness_npm * hand_speed_mps * (latency_p99_s + search_period_s + lockstep_delay_s);
  double worst_n = 0.0;
  double largest_n = 0.0;
  std::size_t worst_tick = 0;
  // Before its first set a run renders nothing: the first set's forces appear as a step, in each
  // run at its own first adoption. Those ticks differ by less than the latency bound's time; the
  // forces are compared from the later of the two on, when both runs track minima.
  const auto first_adopted = [](const hil::RunResult& r) {
    std::int64_t first = std::numeric_limits<std::int64_t>::max();
    for (const hil::RecordedSet& s : r.sets) {
      if (s.adopted_tick > 0) first = std::min(first, s.adopted_tick);
    }
    return first;
  };
  const std::int64_t first_in_process = first_adopted(in_process);
  const std::int64_t first_split = first_adopted(split);
  EXPECT_LE(static_cast<double>(std::abs(first_split - first_in_process)) * dt,
            latency_p99_s + search_period_s + lockstep_delay_s);
  const std::size_t n = std::min(in_process.telemetry.size(), split.telemetry.size());
  for (auto k = static_cast<std::size_t>(std::max(first_in_process, first_split) - 1); k < n; ++k) {
    const hil::TickTelemetry& a = in_process.telemetry[k];
    const hil::TickTelemetry& b = split.telemetry[k];
    ASSERT_EQ(a.tick, b.tick);
    for (std::size_t l = 0; l < a.link_force_W_n.size(); ++l) {
      const double fa = Eigen::Map<const Eigen::Vector3d>(a.link_force_W_n[l].data()).norm();
      const double fb = Eigen::Map<const Eigen::Vector3d>(b.link_force_W_n[l].data()).norm();
      largest_n = std::max(largest_n, fa);
      if (std::abs(fa - fb) > worst_n) {
        worst_n = std::abs(fa - fb);
        worst_tick = k + 1;
      }
    }
  }
  std::cout << "latency p50 " << quantile(age_s, 0.5) * 1e3 << " ms, p99 " << latency_p99_s * 1e3 << " ms over "
            << age_s.size() << " sets; hand speed " << hand_speed_mps << " m/s; tolerance " << tolerance_n
            << " N; largest difference " << worst_n << " N at tick " << worst_tick << " (largest force " << largest_n
            << " N)\n";
  EXPECT_GT(largest_n, 1.0) << "the scenario should bring the arm into contact";
  EXPECT_LE(worst_n, tolerance_n);
}

// The global node killed during a real-time run of the local node: its heartbeat stops, and
// after peer_heartbeat_timeout_s the supervisor trips with communication lost (exit 1).
TEST_F(LcmSplitCli, KillingTheGlobalNodeInRealTimeIsCommunicationLoss) {
  Process global({"--quiet", "global", "--lcm-url", kUrl, "--idle-exit", "10"}, dir_ / "global.txt");
  Process local({"--quiet", "local", "--io", "sim", "--lcm-url", kUrl, "--clock", "realtime", "--duration", "4",
                 "--user", (dir_ / "hold.yaml").string(), "--start-posture", "reach_valve", "--seed", "3", "--out",
                 (dir_ / "local").string()},
                dir_ / "local.txt");
  ASSERT_TRUE(global.waitForOutput("first live joint state", 20.0)) << global.output();
  std::this_thread::sleep_for(std::chrono::milliseconds(800));
  global.kill();
  EXPECT_EQ(global.wait(), -SIGKILL);
  EXPECT_EQ(local.wait(), 1) << local.output();
  std::ifstream summary(dir_ / "local" / "summary.json");
  std::stringstream s;
  s << summary.rdbuf();
  EXPECT_NE(s.str().find("\"tripped\": true"), std::string::npos) << s.str().substr(0, 2000);
  EXPECT_NE(s.str().find("\"trip_cause\": \"communication lost: a peer node's heartbeat stopped\""), std::string::npos)
      << s.str().substr(0, 2000);
}

TEST_F(LcmSplitCli, KillingThePlantNodeFaultsTheRun) {
  Process plant(plantArgs("5"), dir_ / "plant.txt");
  Process run({"--quiet", "run", "--io", "lcm", "--lcm-url", kUrl, "--clock", "lockstep", "--duration", "20",
               "--no-oracle", "--user", (dir_ / "hold.yaml").string(), "--start-posture", "reach_valve", "--seed", "3",
               "--out", (dir_ / "run").string()},
              dir_ / "run.txt");
  ASSERT_TRUE(plant.waitForOutput("first command", 20.0)) << plant.output();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  plant.kill();
  EXPECT_EQ(plant.wait(), -SIGKILL);
  const int code = run.wait();
  EXPECT_EQ(code, 1) << run.output();
  // The device fault trips the supervisor; the summary names the cause.
  std::ifstream summary(dir_ / "run" / "summary.json");
  std::stringstream s;
  s << summary.rdbuf();
  EXPECT_NE(s.str().find("\"tripped\": true"), std::string::npos) << s.str().substr(0, 2000);
  EXPECT_NE(s.str().find("\"trip_cause\": \"communication lost\""), std::string::npos) << s.str().substr(0, 2000);
}

TEST_F(LcmSplitCli, KillingTheRunMakesThePlantNodesWatchdogPutOutTheSafeOutputs) {
  Process plant(plantArgs("1"), dir_ / "plant.txt");
  Process run(
      {"--quiet", "run", "--io", "lcm", "--lcm-url", kUrl, "--clock", "lockstep", "--duration", "20", "--no-oracle",
       "--user", (dir_ / "hold.yaml").string(), "--start-posture", "reach_valve", "--out", (dir_ / "run").string()},
      dir_ / "run.txt");
  ASSERT_TRUE(plant.waitForOutput("amplifiers enabled", 20.0)) << plant.output() << run.output();
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  run.kill();
  EXPECT_EQ(run.wait(), -SIGKILL);
  EXPECT_EQ(plant.wait(), 0) << plant.output();
  const std::string out = plant.output();
  EXPECT_NE(out.find("watchdog: no command for 0.05 s: safe outputs"), std::string::npos) << out;
  EXPECT_NE(out.find("outputs safe at exit"), std::string::npos) << out;
}

// Static holds over LCM on a plant node whose arm (--config) is not the model the holds are
// fitted to: the fitted arm predicts the node's arm's gravity at postures it never held, to half
// a load-cell step, as the holds taken in process do.
TEST_F(LcmSplitCli, GravityHoldsOnThePlantNodePredictTheNodesArmsGravity) {
  const test::CliResult truth_run =
      test::runFullarm("gravity --postures 10 --quiet --out " + (dir_ / "truth").string());
  ASSERT_EQ(truth_run.exit_code, 0) << truth_run.output;
  const auto truth_file = dir_ / "truth" / "arm.yaml";
  Process plant({"--quiet", "plant", "serve", "--lcm-url", kUrl, "--no-user", "--config", truth_file.string(),
                 "--idle-exit", "2"},
                dir_ / "plant.txt");
  Process gravity({"gravity", "--io", "lcm", "--lcm-url", kUrl, "--postures", "6", "--seed", "2", "--out",
                   (dir_ / "held").string()},
                  dir_ / "gravity.txt");
  ASSERT_EQ(gravity.wait(), 0) << gravity.output() << plant.output();
  EXPECT_NE(gravity.output().find("posture 6 of 6, from below"), std::string::npos) << gravity.output();
  EXPECT_EQ(plant.wait(), 0) << plant.output();
  EXPECT_NE(plant.output().find("0 stale, 0 rejected"), std::string::npos) << plant.output();
  EXPECT_NE(plant.output().find("outputs safe at exit"), std::string::npos) << plant.output();

  const arm::ArmModel truth = arm::loadArmModel(truth_file);
  const arm::ArmModel fitted = arm::loadArmModel(dir_ / "held" / "arm.yaml");
  const auto gravityAt = [](const arm::ArmModel& model, const Eigen::VectorXd& q) {
    arm::ArmData data(model);
    arm::computeGravityTorques(model, data, q);
    return Eigen::VectorXd(data.tau_gravity);
  };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  double worst = 0.0;
  for (int p = 0; p < 20; ++p) {
    Eigen::VectorXd q = truth.defaultPosture();
    for (int k = 0; k < 7; ++k) {
      const auto& limits = truth.joints[static_cast<std::size_t>(k)].limits;
      q[k] = limits.min_rad + 0.1 + unit(rng) * (limits.max_rad - limits.min_rad - 0.2);
    }
    worst = std::max(worst, (gravityAt(fitted, q) - gravityAt(truth, q)).head(7).cwiseAbs().maxCoeff());
  }
  std::printf("largest held-out gravity error over LCM: %.4f N m\n", worst);
  EXPECT_LT(worst, 0.5 * 0.02488643);  // half a step of the 12-bit elbow load cell
}

// The two identification experiments over LCM, every joint of the node held: the node serves
// exactly the commands of the two experiments, run in one activation (each a 1 s settle and the
// excitation, then the one safe output sent at the end), none stale or damaged, and ends with
// safe outputs; the logs carry the excitation on the driven joint's hold law; the command ends in
// its fit and verdict (exit 0 or 1, not a device error).
TEST_F(LcmSplitCli, IdentifyRunsItsExperimentsOnThePlantNode) {
  Process plant({"--quiet", "plant", "serve", "--lcm-url", kUrl, "--no-user", "--idle-exit", "2"}, dir_ / "plant.txt");
  Process identify({"identify", "--io", "lcm", "--lcm-url", kUrl, "--duration", "1", "--out", (dir_ / "id").string()},
                   dir_ / "identify.txt");
  const int code = identify.wait();
  EXPECT_TRUE(code == 0 || code == 1) << identify.output();
  // The progress line says how long the run takes: two experiments of a 1 s settle and 1 s each.
  EXPECT_NE(identify.output().find("through lcm, 4 s of control time"), std::string::npos) << identify.output();
  EXPECT_EQ(plant.wait(), 0) << plant.output();
  EXPECT_NE(plant.output().find("4001 commands served, 0 stale, 0 rejected"), std::string::npos) << plant.output();
  EXPECT_NE(plant.output().find("outputs safe at exit"), std::string::npos) << plant.output();
  std::ifstream summary(dir_ / "id" / "summary.json");
  std::stringstream s;
  s << summary.rdbuf();
  const nlohmann::json j = nlohmann::json::parse(s.str());
  const nlohmann::json& experiments = j["results"]["identify"]["experiments"];
  ASSERT_EQ(experiments.size(), 2u);
  for (const nlohmann::json& e : experiments) {
    EXPECT_EQ(e["samples"], 1000) << e.dump();
    EXPECT_EQ(e["completed"], true) << e.dump();
    EXPECT_NEAR(e["hold_gain_v_per_rad"].get<double>(), 10.0, 1e-6) << e.dump();
  }
  std::ifstream report(dir_ / "id" / "report.html");
  std::stringstream html;
  html << report.rdbuf();
  EXPECT_NE(html.str().find("on a plant node over LCM"), std::string::npos);
  EXPECT_NE(html.str().find("the held joints at their mean angles in experiment_fit.csv"), std::string::npos);
  // The held neighbours' coupling, which the single-joint model leaves out, is said in the report,
  // the summary and the command's output.
  EXPECT_NE(html.str().find("The other joints were held, not locked"), std::string::npos);
  EXPECT_TRUE(j["results"]["identify"]["neighbours_held"].get<bool>());
  EXPECT_NE(identify.output().find("note: the other joints were held, not locked"), std::string::npos)
      << identify.output();

  // Each log records every other joint of the node, held, as a held_<joint>_rad column; the summary
  // gives their means over the log.
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  const plant::PlantConfig node_plant = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  const nlohmann::json& result = j["results"]["identify"];
  const char* logs[] = {"experiment_fit.csv", "experiment_validation.csv"};
  for (std::size_t e = 0; e < 2; ++e) {
    const identification::SignalTable log = identification::readSignalCsv(dir_ / "id" / logs[e], {});
    const nlohmann::json& held = experiments[e]["held_joints_rad"];
    EXPECT_EQ(held.size(), node_plant.joints.size() - 1) << held.dump();
    for (const plant::JointParams& joint : node_plant.joints) {
      if (joint.name == "R_EB") {
        EXPECT_FALSE(log.has("held_R_EB_rad"));
        continue;
      }
      const std::vector<double>& column = log.column("held_" + joint.name + "_rad");
      double sum = 0.0;
      for (double v : column) sum += v;
      EXPECT_NEAR(held[joint.name].get<double>(), sum / static_cast<double>(column.size()), 1e-12) << joint.name;
    }
  }
  // The fit's start: KDL's link inertia and gravity load at the posture the first log records
  // (the elbow at its hold angle, every held joint at its mean, any other at the default).
  Eigen::VectorXd q = model.defaultPosture();
  for (const auto& [name, angle] : experiments[0]["held_joints_rad"].items()) q[model.jointIndex(name)] = angle;
  const int elbow = model.jointIndex("R_EB");
  q[elbow] = experiments[0]["hold_rad"].get<double>();
  const arm::test::KdlJointAtRest kdl = arm::test::kdlJointAtRest(model, q, elbow);
  const double start_load = result["start_gravity_load_nm"].get<double>();
  EXPECT_NEAR(start_load, kdl.gravity_nm, 1e-9 * std::abs(kdl.gravity_nm));
  EXPECT_NEAR(result["start_link_inertia_kgm2"].get<double>(), kdl.inertia_kgm2, 1e-9 * kdl.inertia_kgm2);

  // Fitting the written logs again starts from the same posture and reaches the same parameters.
  const test::CliResult refit =
      test::runFullarm("identify --quiet --joint EB --log " + (dir_ / "id" / logs[0]).string() + " " +
                       (dir_ / "id" / logs[1]).string() + " --out " + (dir_ / "refit").string());
  ASSERT_EQ(refit.exit_code, code) << refit.output;
  std::ifstream refit_summary(dir_ / "refit" / "summary.json");
  const nlohmann::json again = nlohmann::json::parse(refit_summary)["results"]["identify"];
  EXPECT_EQ(again["start_gravity_load_nm"].get<double>(), start_load);
  for (const auto& [name, parameter] : result["parameters"].items()) {
    EXPECT_EQ(again["parameters"][name]["value"].get<double>(), parameter["value"].get<double>()) << name;
  }
}

// A node with a scripted user strapped in (`plant serve` without --no-user): identify and gravity
// refuse it before anything moves (exit 2), naming `plant serve --no-user`; the node serves no
// command.
TEST_F(LcmSplitCli, IdentifyAndGravityRefuseANodeWithAScriptedUser) {
  Process plant({"--quiet", "plant", "serve", "--lcm-url", kUrl, "--idle-exit", "5"}, dir_ / "plant.txt");
  const std::string url = " --io lcm --lcm-url '" + std::string(kUrl) + "'";
  const test::CliResult identify = test::runFullarm("identify" + url + " --duration 1 --out " + (dir_ / "id").string());
  const test::CliResult gravity = test::runFullarm("gravity" + url + " --postures 2 --out " + (dir_ / "g").string());
  plant.terminate();
  EXPECT_EQ(plant.wait(), 0) << plant.output();
  for (const test::CliResult* r : {&identify, &gravity}) {
    EXPECT_EQ(r->exit_code, 2) << r->output;
    EXPECT_NE(r->output.find("the node at " + std::string(kUrl) + " has a scripted user strapped in"),
              std::string::npos)
        << r->output;
    EXPECT_NE(r->output.find("`fullarm plant serve --no-user`"), std::string::npos) << r->output;
  }
  EXPECT_NE(plant.output().find("a scripted user strapped in"), std::string::npos) << plant.output();
  EXPECT_NE(plant.output().find(" 0 commands served"), std::string::npos) << plant.output();
}

// A node serving the same joints from another plant file (the elbow's viscous friction changed):
// identify and gravity over it refuse --plant naming both files, before anything moves.
TEST_F(LcmSplitCli, IdentifyAndGravityRefuseAPlantFileOtherThanTheNodes) {
  std::ifstream in(arm::test::sourcePath("config/dts_plant.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string edited = text.str();
  const std::size_t eb = edited.find("  - name: R_EB");
  const std::size_t viscous = edited.find("viscous_nms_per_rad:", eb);
  ASSERT_TRUE(eb != std::string::npos && viscous != std::string::npos);
  const std::size_t value = viscous + std::string("viscous_nms_per_rad:").size();
  const std::size_t end = edited.find_first_of(",}\n", value);
  edited.replace(value, end - value, " 0.2");
  const auto other = dir_ / "plant_other.yaml";
  std::ofstream(other) << edited;
  Process plant({"--quiet", "plant", "serve", "--lcm-url", kUrl, "--no-user", "--plant-config", other.string(),
                 "--idle-exit", "5"},
                dir_ / "plant.txt");
  const std::string url = " --io lcm --lcm-url '" + std::string(kUrl) + "'";
  const test::CliResult identify = test::runFullarm("identify" + url + " --duration 1 --out " + (dir_ / "id").string());
  const test::CliResult gravity = test::runFullarm("gravity" + url + " --postures 2 --out " + (dir_ / "g").string());
  plant.terminate();
  EXPECT_EQ(plant.wait(), 0) << plant.output();
  for (const test::CliResult* r : {&identify, &gravity}) {
    EXPECT_EQ(r->exit_code, 2) << r->output;
    EXPECT_NE(r->output.find("--plant"), std::string::npos) << r->output;
    EXPECT_NE(r->output.find("dts_plant.yaml"), std::string::npos) << r->output;
    EXPECT_NE(r->output.find("plant_other.yaml sha256"), std::string::npos) << r->output;
  }
  EXPECT_NE(plant.output().find(" 0 commands served"), std::string::npos) << plant.output();
  // Given the node's file, identify runs.
  Process again({"--quiet", "plant", "serve", "--lcm-url", kUrl, "--no-user", "--plant-config", other.string(),
                 "--idle-exit", "2"},
                dir_ / "plant2.txt");
  // On a simulated node no real arm moves: --confirm-arm-motion is refused, naming the node.
  const test::CliResult confirmed =
      test::runFullarm("identify" + url + " --plant " + other.string() + " --hold-angle 1.2 --confirm-arm-motion" +
                       " --duration 1 --quiet --out " + (dir_ / "id_confirmed").string());
  EXPECT_EQ(confirmed.exit_code, 2) << confirmed.output;
  EXPECT_NE(confirmed.output.find("--confirm-arm-motion: the node at " + std::string(kUrl) + " serves a simulated arm"),
            std::string::npos)
      << confirmed.output;
  const test::CliResult same = test::runFullarm("identify" + url + " --plant " + other.string() +
                                                " --duration 1 --quiet --out " + (dir_ / "id2").string());
  EXPECT_TRUE(same.exit_code == 0 || same.exit_code == 1) << same.output;
  EXPECT_EQ(again.wait(), 0) << again.output();
}

// A node that says it serves the real arm (simulated = false; here the simulated DTS served from
// this process, saying so): gravity's holds and identify's move to a hold angle need
// --confirm-arm-motion, as on --io comedi.
TEST_F(LcmSplitCli, GravityOnANodeServingTheRealArmNeedsConfirmArmMotion) {
  hil::RunOptions options;  // the shipped files
  options.scripted_user = false;
  hil::HilSession session(options);
  hil::PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  po.info = hil::describeSessionDevice(session);
  po.info.simulated = false;
  hil::LcmPlantNode node(session.device(), po);
  std::atomic<bool> stop{false};
  hil::PlantNodeResult served;
  std::thread thread([&] { served = node.serve([&stop] { return stop.load(); }); });
  const test::CliResult r = test::runFullarm("gravity --io lcm --lcm-url '" + std::string(kUrl) +
                                             "' --postures 2 --out " + (dir_ / "g").string());
  const test::CliResult id = test::runFullarm("identify --io lcm --lcm-url '" + std::string(kUrl) +
                                              "' --hold-angle 1.2 --duration 1 --out " + (dir_ / "id").string());
  stop = true;
  thread.join();
  for (const test::CliResult* result : {&r, &id}) {
    EXPECT_EQ(result->exit_code, 2) << result->output;
    EXPECT_NE(result->output.find("--confirm-arm-motion"), std::string::npos) << result->output;
    EXPECT_NE(result->output.find("the node at " + std::string(kUrl) + " says it is not simulated"), std::string::npos)
        << result->output;
  }
  EXPECT_EQ(served.commands, 0u) << "nothing moved";
}

// A node serving another plant file's joints (two joints' entries swapped: the device's order
// differs): the run stops before its first tick (exit 2), naming the node's URL, what it serves
// and what the run expects.
TEST_F(LcmSplitCli, ARunAgainstANodeServingOtherJointsExitsTwoNamingBoth) {
  std::ifstream in(arm::test::sourcePath("config/dts_plant.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  const std::string full = text.str();
  const std::size_t saa = full.find("  - name: R_SAA");
  const std::size_t hr = full.find("  - name: R_HR");
  const std::size_t eb = full.find("  - name: R_EB");
  ASSERT_TRUE(saa != std::string::npos && saa < hr && hr < eb && eb != std::string::npos);
  const auto swapped = dir_ / "plant_swapped.yaml";
  std::ofstream(swapped) << full.substr(0, saa) << full.substr(hr, eb - hr) << full.substr(saa, hr - saa)
                         << full.substr(eb);
  Process plant(
      {"--quiet", "plant", "serve", "--lcm-url", kUrl, "--plant-config", swapped.string(), "--idle-exit", "5"},
      dir_ / "plant.txt");
  const test::CliResult r = test::runFullarm("--quiet run --io lcm --lcm-url '" + std::string(kUrl) +
                                             "' --clock lockstep --duration 0.1 --no-oracle " + scenario() + " --out " +
                                             (dir_ / "run").string());
  plant.terminate();
  (void)plant.wait();
  EXPECT_EQ(r.exit_code, 2) << r.output << plant.output();
  EXPECT_NE(r.output.find("the node at " + std::string(kUrl) +
                          " serves joints R_SFE,R_HR,R_SAA,R_EB,R_WR,R_WFE,R_WAA every 1000 us; expected "
                          "R_SFE,R_SAA,R_HR,R_EB,R_WR,R_WFE,R_WAA every 1000 us"),
            std::string::npos)
      << r.output << plant.output();
  EXPECT_NE(plant.output().find(" 0 commands served"), std::string::npos) << plant.output();
}

// No node at the URL: a clear device error naming the URL (exit 2), before anything moves.
TEST_F(LcmSplitCli, IdentifyWithoutAPlantNodeExitsTwoNamingTheUrl) {
  const test::CliResult r =
      test::runFullarm("identify --io lcm --lcm-url '" + std::string(kUrl) + "' --out " + (dir_ / "id").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("239.255.76.98:7698"), std::string::npos) << r.output;
}

}  // namespace
}  // namespace fullarm::app
