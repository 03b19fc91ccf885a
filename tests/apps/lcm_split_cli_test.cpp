// `fullarm plant serve`, `fullarm global`, `fullarm run --io lcm` and `fullarm local` as separate
// processes over LCM udpm, inside a private network namespace the test makes (loopback only). A
// lockstep run over the plant node, and the local node over the plant and global nodes, write the
// in-process run's log bit for bit (every event but the header, which names the I/O back-end); killing the plant node faults the run (communication lost, supervisor trip, exit 1);
// killing the run makes the plant node's watchdog put out the safe outputs.

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include "cli_runner.hpp"
#include "fullarm/hil/run_log.hpp"
#include "private_network.hpp"

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
    return {"--quiet", "plant", "serve", "--lcm-url", kUrl, "--user", (dir_ / "hold.yaml").string(), "--start-posture",
            "reach_valve", "--seed", "3", "--watchdog", "0.05", "--idle-exit", idle_exit};
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

TEST_F(LcmSplitCli, KillingThePlantNodeFaultsTheRun) {
  Process plant(plantArgs("5"), dir_ / "plant.txt");
  Process run({"--quiet", "run", "--io", "lcm", "--lcm-url", kUrl, "--clock", "lockstep", "--duration", "20", "--no-oracle",
               "--user", (dir_ / "hold.yaml").string(), "--start-posture", "reach_valve", "--seed", "3", "--out",
               (dir_ / "run").string()},
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
  Process run({"--quiet", "run", "--io", "lcm", "--lcm-url", kUrl, "--clock", "lockstep", "--duration", "20", "--no-oracle",
               "--user", (dir_ / "hold.yaml").string(), "--start-posture", "reach_valve", "--out",
               (dir_ / "run").string()},
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

}  // namespace
}  // namespace fullarm::app
