// The fake DAQ: the comedi back-end's own code on a stand-in for comedilib with Comedi's
// semantics, wired to the simulated DTS. The same closed loop as the sim back-end, bit for bit,
// when both use the channel map's converters; readings at the range ends out of range; clear
// errors for a missing device and a channel the board lacks; chamber pressure channels read
// through their calibration, and refused on a joint without transducers; the enable line as a
// heartbeat; and a process killed while driving the arm: the analog outputs hold their last codes
// and the rig's hardware watchdog drops the amplifier enable.

#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <string>
#include <thread>

#include "fullarm/core/config_error.hpp"
#include "fullarm/hil/fake_daq.hpp"
#include "fullarm/hil/sim_io.hpp"
#include "hil_fixture.hpp"
#include "run_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::hil {
namespace {

constexpr double kPeriod_s = 1e-3;

std::int64_t nowNs() {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

TEST(FakeDaq, GivesTheSameClosedLoopAsSimWithTheSameConverters) {
  RunOptions sim = test::shippedRun(3.0);
  sim.oracle = false;
  sim.sim_uses_daq_converters = true;
  RunOptions fake = sim;
  fake.io = IoKind::kFakeDaq;
  const RunResult a = runHil(sim);
  const RunResult b = runHil(fake);
  ASSERT_EQ(a.telemetry.size(), b.telemetry.size());
  EXPECT_EQ(a.io_name, "sim");
  EXPECT_EQ(b.io_name, "fakedaq");
  bool driven = false;
  for (std::size_t k = 0; k < a.telemetry.size(); ++k) {
    ASSERT_EQ(a.telemetry[k].q_rad, b.telemetry[k].q_rad) << "tick " << k + 1;
    ASSERT_EQ(a.telemetry[k].tau_load_cell_nm, b.telemetry[k].tau_load_cell_nm) << "tick " << k + 1;
    ASSERT_EQ(a.telemetry[k].valve_v, b.telemetry[k].valve_v) << "tick " << k + 1;
    ASSERT_EQ(a.telemetry[k].tau_contact_nm, b.telemetry[k].tau_contact_nm) << "tick " << k + 1;
    for (const double v : a.telemetry[k].valve_v) driven = driven || v != 0.0;
  }
  EXPECT_TRUE(driven);
  EXPECT_FALSE(b.tripped);
}

struct Bench {
  Bench() : arm(test::makeArm(1)), board(test::daqConfig()), rig(board, *arm, test::daqConfig(), 0.05) {}
  std::unique_ptr<SimulatedArm> arm;
  FakeDaqBoard board;
  FakeDaqRig rig;
};

TEST(FakeDaq, ReadingsAtTheRangeEndsAreOutOfRange) {
  Bench bench;
  auto device = makeFakeDaqIoDevice(test::daqConfig(), test::model(), kPeriod_s, {}, nullptr);  // no world: codes stay
  device->configure();
  JointSample s;
  ASSERT_TRUE(device->read(s).ok());
  EXPECT_TRUE(s.q_rad.allFinite());
  EXPECT_EQ(s.out_of_range_mask, 0u);
  const DaqConfig& map = test::daqConfig();
  bench.board.state().ai_codes[map.joints[2].potentiometer.channel] = 0;
  bench.board.state().ai_codes[map.joints[5].load_cell.channel] = map.fake_ai.maxdata;
  ASSERT_TRUE(device->read(s).ok());
  EXPECT_TRUE(std::isnan(s.q_rad[2]));
  EXPECT_TRUE(std::isnan(s.tau_load_cell_nm[5]));
  EXPECT_EQ(s.out_of_range_mask, (1u << 2) | (1u << 5));
}

// The elbow's chamber pressure transducers wired to the board, on a plant whose elbow has them.
struct PressureRig {
  plant::PlantConfig plant = test::plantWithElbowTransducers();
  DaqConfig map = test::daqConfigWithElbowPressures();
};

// The comedi back-end reads the transducers through their channels' calibration, within half a
// converter code of the plant's own readings; only the wired joint's pressure bit is set; a
// saturated transducer reads NaN without flagging the joint's angle or torque out of range.
TEST(FakeDaq, ChamberPressureChannelsReadThePlantsTransducers) {
  const PressureRig wiring;
  const double half_code_pa = test::kElbowPressureHalfCodePa;
  {
    SimulatedArm arm(test::model(), wiring.plant, test::restPosture(), kPeriod_s, 1);
    FakeDaqBoard board(wiring.map);
    FakeDaqRig rig(board, arm, wiring.map, 0.05);
    auto device = makeFakeDaqIoDevice(wiring.map, test::model(), kPeriod_s, {}, &rig);
    device->configure();
    JointSample s;
    for (int tick = 0; tick < 50; ++tick) {
      ASSERT_TRUE(device->read(s).ok());
      ASSERT_EQ(s.pressure_mask, 1u << 3);
      const plant::JointMeasurement& m = arm.reading(3);
      ASSERT_TRUE(m.pressures);
      EXPECT_NEAR(s.p_a_pa[3], m.p_a_pa, half_code_pa) << "tick " << tick;
      EXPECT_NEAR(s.p_b_pa[3], m.p_b_pa, half_code_pa) << "tick " << tick;
    }
    // Holding the forearm against gravity: the chambers are pressurised and differ.
    EXPECT_GT(s.p_a_pa[3] + s.p_b_pa[3], 1.0e6);
    EXPECT_GT(std::abs(s.p_a_pa[3] - s.p_b_pa[3]), 10.0 * half_code_pa);
  }
  FakeDaqBoard board(wiring.map);
  auto device = makeFakeDaqIoDevice(wiring.map, test::model(), kPeriod_s, {}, nullptr);  // codes stay
  device->configure();
  const DaqJoint& elbow = wiring.map.joints[3];
  board.state().ai_codes[elbow.potentiometer.channel] = 2000;
  board.state().ai_codes[elbow.load_cell.channel] = 2000;
  board.state().ai_codes[7] = wiring.map.fake_ai.maxdata;
  board.state().ai_codes[15] = 3000;
  JointSample s;
  ASSERT_TRUE(device->read(s).ok());
  EXPECT_EQ(s.pressure_mask, 1u << 3);
  EXPECT_TRUE(std::isfinite(s.q_rad[3]));
  EXPECT_TRUE(std::isnan(s.p_a_pa[3]));
  EXPECT_DOUBLE_EQ(s.p_b_pa[3], 2.5e6 * (3000.0 / 4095.0 * 20.0 - 10.0));
  EXPECT_EQ(s.out_of_range_mask & (1u << 3), 0u);
}

// Pressure channels on a joint whose plant has no transducers: the fake DAQ's rig and the sim
// back-end both refuse the map, naming its file, the key and the joint.
TEST(FakeDaq, PressureChannelsOnAJointWithoutTransducersAreRefused) {
  const PressureRig wiring;
  SimulatedArm arm(test::model(), test::plantConfig(), test::restPosture(), kPeriod_s, 1);
  FakeDaqBoard board(wiring.map);
  const auto expect_refused = [](const std::function<void()>& build, const std::string& who) {
    try {
      build();
      FAIL() << who << " accepted pressure channels without transducers";
    } catch (const core::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_EQ(e.keyPath(), "joints[3].pressure_a") << what;
      EXPECT_NE(what.find(who), std::string::npos) << what;
      EXPECT_NE(what.find("dts_daq.yaml"), std::string::npos) << what;
      EXPECT_NE(what.find("pressure channels for R_EB"), std::string::npos) << what;
      EXPECT_NE(what.find("pressure_full_scale_pa"), std::string::npos) << what;
    }
  };
  expect_refused([&] { FakeDaqRig rig(board, arm, wiring.map, 0.05); }, "fake DAQ");
  SimIoOptions options;
  options.converters = &wiring.map;
  expect_refused([&] { SimIoDevice device(arm, options, {}); }, "sim I/O");
}

TEST(FakeDaq, AMissingDeviceOrChannelIsAClearError) {
  DaqConfig map = test::daqConfig();
  map.device = "/dev/comedi7";
  auto missing = makeFakeDaqIoDevice(map, test::model(), kPeriod_s, {}, nullptr);
  try {
    missing->configure();
    FAIL() << "a missing board must be an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/comedi7"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("dts_daq.yaml"), std::string::npos) << e.what();
  }
  DaqConfig small = test::daqConfig();
  small.fake_ai_channels = 12;  // the board lacks the load cells' channels 12-14
  FakeDaqBoard board(small);
  auto device = makeFakeDaqIoDevice(test::daqConfig(), test::model(), kPeriod_s, {}, nullptr);
  try {
    device->configure();
    FAIL() << "a channel the board lacks must be an error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("load_cell: channel 12 does not exist"), std::string::npos) << e.what();
  }
  // The real back-end on a machine without the board.
  RunOptions o = test::shippedRun(1.0);
  o.io = IoKind::kComedi;
  o.clock = ClockKind::kRealtime;
  HilSession session(o);
  try {
    (void)session.run();
    FAIL() << "no board: the run must not start";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("/dev/comedi0"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("cannot open the Comedi device"), std::string::npos) << e.what();
  }
}

TEST(FakeDaq, TheEnableLineBeatsOnlyWhileActiveAndAStaleCommandIsNeverApplied) {
  Bench bench;
  IoSafetyParams safety;
  safety.ramp_in_s = 0.0;
  auto device = makeFakeDaqIoDevice(test::daqConfig(), test::model(), kPeriod_s, safety, &bench.rig);
  const DaqConfig& map = test::daqConfig();
  const std::uint32_t zero_code = voltsToCode(0.0, map.fake_ao);
  device->configure();
  const int n = device->numJoints();
  JointSample s;
  ASSERT_TRUE(device->read(s).ok());
  ASSERT_TRUE(device->write(IoVector::Constant(n, 3.0)).ok());  // a stale command, inactive
  EXPECT_EQ(bench.board.state().ao_codes[map.joints[0].valve.channel], zero_code);
  EXPECT_EQ(bench.board.state().enable_changes, 0u);
  device->activate();
  ASSERT_TRUE(device->read(s).ok());
  ASSERT_TRUE(device->write(IoVector::Constant(n, 3.0)).ok());
  EXPECT_EQ(bench.board.state().ao_codes[map.joints[0].valve.channel], zero_code) << "the first write is the safe one";
  EXPECT_EQ(bench.board.state().enable_changes, 1u);
  for (int k = 0; k < 10; ++k) {
    ASSERT_TRUE(device->read(s).ok());
    ASSERT_TRUE(device->write(IoVector::Constant(n, 3.0)).ok());
  }
  EXPECT_EQ(bench.board.state().ao_codes[map.joints[0].valve.channel], voltsToCode(3.0, map.fake_ao));
  EXPECT_EQ(bench.board.state().enable_changes, 11u);
  EXPECT_TRUE(amplifierEnabledPeriods(bench.board.state(), 50));
  device->fault("test");
  for (int k = 0; k < 60; ++k) {
    ASSERT_TRUE(device->read(s).ok());
    (void)device->write(IoVector::Constant(n, 3.0));
  }
  EXPECT_EQ(bench.board.state().enable_changes, 11u) << "a faulted device lets the line rest";
  EXPECT_EQ(bench.board.state().ao_codes[map.joints[0].valve.channel], zero_code);
  EXPECT_FALSE(amplifierEnabledPeriods(bench.board.state(), 50));
}

TEST(FakeDaq, AKilledProcessLeavesTheOutputsHoldingAndTheWatchdogDropsTheEnable) {
  const auto dir = fullarm::test::scratchDir("hil_fakedaq_kill");
  const auto state_file = dir / "board.state";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The child drives the arm in real time on the fake board kept in the file, until killed.
    RunOptions o = test::shippedRun(20.0);
    o.io = IoKind::kFakeDaq;
    o.clock = ClockKind::kRealtime;
    o.oracle = false;
    o.fakedaq_state_file = state_file;
    try {
      (void)runHil(o);
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(0);
  }
  const DaqConfig& map = test::daqConfig();
  const std::uint32_t zero_code = voltsToCode(0.0, map.fake_ao);
  const double timeout_s = map.fake_watchdog_timeout_s;
  // Wait until the child drives the valves (after the start-up guard and the ramp-in).
  std::shared_ptr<const FakeDaqState> board;
  bool driving = false;
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(15);
  while (!driving && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    try {
      if (!board) board = FakeDaqBoard::inspect(state_file);
    } catch (const std::runtime_error&) {
      continue;  // not created yet
    }
    int driven = 0;
    for (const DaqJoint& j : map.joints) driven += board->ao_codes[j.valve.channel] != zero_code ? 1 : 0;
    driving = board->enable_changes > 1000 && driven > 0;
  }
  ASSERT_TRUE(driving) << "the child never drove the valves";
  EXPECT_TRUE(amplifierEnabled(*board, nowNs(), timeout_s));
  ASSERT_EQ(::kill(child, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  std::uint32_t held[kFakeDaqMaxAnalogOutputs];
  std::copy(std::begin(board->ao_codes), std::end(board->ao_codes), std::begin(held));
  const std::uint64_t changes = board->enable_changes;
  std::this_thread::sleep_for(std::chrono::duration<double>(3 * timeout_s));
  // Comedi's analog outputs hold their last value when the process dies ...
  int holding_non_null = 0;
  for (const DaqJoint& j : map.joints) {
    EXPECT_EQ(board->ao_codes[j.valve.channel], held[j.valve.channel]);
    holding_non_null += held[j.valve.channel] != zero_code ? 1 : 0;
  }
  EXPECT_GT(holding_non_null, 0) << "the valves hold a live command";
  // ... so only the enable line and the hardware watchdog make the arm safe: the line stopped,
  // the watchdog dropped the amplifier enable.
  EXPECT_EQ(board->enable_changes, changes);
  EXPECT_FALSE(amplifierEnabled(*board, nowNs(), timeout_s));
}

}  // namespace
}  // namespace fullarm::hil
