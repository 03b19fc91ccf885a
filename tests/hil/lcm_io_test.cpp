// Remote I/O over LCM udpm, inside a private network namespace the test makes (loopback only:
// nothing can leave the process's own namespace). The plant node serves from a thread with its
// own LCM instances, exactly as it would from another process. A lockstep run over the remote
// device equals the in-process run bit for bit; the plant node's watchdog puts out the safe
// output when commands stop; a read without an answer faults the device.

#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <fstream>
#include <thread>

#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/sim_io.hpp"
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

TEST_F(LcmIo, ARunOverRemoteIoEqualsTheInProcessRunBitForBit) {
  // The hand held against the valve wheel: in contact after the start-up.
  const auto dir = fullarm::test::scratchDir("hil_lcm_io");
  {
    std::ofstream user(dir / "hold.yaml");
    user << "schema_version: 1\nname: hold\narm_impedance: {stiffness_npm: 300.0, damping_nspm: 30.0}\n"
            "push_force_n: 15.0\nhand_path:\n  - {t_s: 0.0, hand_m: [0.101, 0.568, 1.251]}\n";
  }
  RunOptions local = test::shippedRun(1.5);
  local.oracle = false;
  local.start_posture = "reach_valve";
  local.user = dir / "hold.yaml";
  const RunResult in_process = runHil(local);

  RunOptions plant_options = local;  // the plant node's session: the same files and seed
  HilSession plant(plant_options);
  PlantNodeOptions node_options;
  node_options.url = kUrl;
  node_options.idle_exit_s = 20.0;
  LcmPlantNode node(plant.device(), node_options);
  std::atomic<bool> stop{false};
  PlantNodeResult served;
  std::thread plant_thread([&] { served = node.serve([&] { return stop.load(); }); });

  local.io = IoKind::kLcm;
  local.lcm_url = kUrl;
  RunResult remote;
  try {
    remote = runHil(local);
  } catch (...) {
    stop = true;
    plant_thread.join();
    throw;
  }
  stop = true;
  plant_thread.join();

  EXPECT_EQ(remote.io_name, "lcm");
  ASSERT_EQ(in_process.telemetry.size(), remote.telemetry.size());
  EXPECT_EQ(served.commands, remote.telemetry.size());
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
    for (const double v : a.valve_v) driven = driven || v != 0.0;
    for (const double t : a.tau_contact_nm) touched = touched || t != 0.0;
  }
  EXPECT_TRUE(driven);
  EXPECT_TRUE(touched) << "the scenario should bring the arm into contact";
  EXPECT_EQ(in_process.tripped, remote.tripped);
}

/// A plant node serving a simulated arm from a thread.
struct PlantThread {
  explicit PlantThread(PlantNodeOptions options)
      : arm(test::makeArm(1)), device(*arm, SimIoOptions{}, IoSafetyParams{}), node(device, std::move(options)) {
    thread = std::thread([this] { result = node.serve([this] { return stop.load(); }); });
  }
  ~PlantThread() { join(); }
  void join() {
    stop = true;
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

TEST_F(LcmIo, AReadWithoutAnAnswerFaultsTheDevice) {
  PlantNodeOptions po;
  po.url = kUrl;
  po.idle_exit_s = 5.0;
  auto plant = std::make_unique<PlantThread>(po);
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, deviceOptions());
  device.configure();
  device.activate();
  JointSample s;
  for (int k = 0; k < 5; ++k) ASSERT_TRUE(device.read(s).ok());
  plant->join();  // the plant node is gone
  const core::RtStatus status = device.read(s);
  EXPECT_FALSE(status.ok());
  EXPECT_NE(status.faults & kFaultDeviceRead, 0u);
  EXPECT_EQ(device.state(), IoState::kFault);
  EXPECT_EQ(device.counters().timeouts, 1u);
  EXPECT_EQ(device.counters().readings, 5u);
}

TEST_F(LcmIo, ConfiguringWithoutAPlantNodeIsADeviceError) {
  LcmIoOptions o = deviceOptions();
  o.connect_timeout_s = 0.2;
  LcmIoDevice device(test::armJoints(), 1e-3, IoSafetyParams{}, o);
  EXPECT_THROW(device.configure(), DeviceError);
}

}  // namespace
}  // namespace fullarm::hil
