// IoDevice's lifecycle and safety policy (safe outputs, no stale command at activation, ramp-in),
// on the sim back-end: the plant, the latency and the DAC model.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "alloc_guard.hpp"
#include "fullarm/hil/fake_daq.hpp"
#include "fullarm/hil/sim_io.hpp"
#include "hil_fixture.hpp"

namespace fullarm::hil {
namespace {

constexpr double kPeriod_s = 1e-3;

IoVector volts(int n, double v) {
  return IoVector::Constant(n, v);
}

TEST(IoDevice, LifecycleAndSafeOutputsOutsideTheActiveState) {
  auto arm = test::makeArm();
  IoSafetyParams safety;
  safety.ramp_in_s = 0.01;
  SimIoDevice device(*arm, {}, safety);
  const int n = device.numJoints();
  JointSample sample;
  EXPECT_EQ(device.state(), IoState::kUnconfigured);
  EXPECT_FALSE(device.read(sample).ok());
  EXPECT_THROW(device.activate(), std::logic_error);

  device.configure();
  EXPECT_EQ(device.state(), IoState::kInactive);
  ASSERT_TRUE(device.read(sample).ok());
  EXPECT_EQ(sample.q_rad.size(), n);
  // Inactive: whatever it is given, the device writes the safe output and keeps the enable still.
  ASSERT_TRUE(device.write(volts(n, 5.0)).ok());
  EXPECT_EQ(device.appliedCommand(), IoVector::Zero(n));
  EXPECT_FALSE(device.enableAsserted());
}

TEST(IoDevice, ActivationWithAStaleCommandPendingStartsFromTheSafeOutputAndRampsIn) {
  auto arm = test::makeArm();
  IoSafetyParams safety;
  safety.ramp_in_s = 0.01;  // 10 periods
  SimIoDevice device(*arm, {}, safety);
  const int n = device.numJoints();
  device.configure();
  // A command written before activation (a stale controller) ...
  ASSERT_TRUE(device.write(volts(n, 4.0)).ok());
  device.activate();
  // ... is not applied: the first write after activation puts out the safe output whatever it
  // is given, with the enable line toggling.
  ASSERT_TRUE(device.write(volts(n, 4.0)).ok());
  EXPECT_EQ(device.appliedCommand(), IoVector::Zero(n));
  EXPECT_TRUE(device.enableAsserted());
  for (int k = 1; k <= 12; ++k) {
    ASSERT_TRUE(device.write(volts(n, 4.0)).ok());
    const double expected = 4.0 * std::min(1.0, k / 10.0);
    EXPECT_NEAR(device.appliedCommand()[0], expected, 1e-12) << "write " << k;
  }
  // Deactivate and activate again: the ramp starts over from null.
  device.deactivate();
  EXPECT_EQ(device.appliedCommand(), IoVector::Zero(n));
  device.activate();
  ASSERT_TRUE(device.write(volts(n, 4.0)).ok());
  EXPECT_EQ(device.appliedCommand(), IoVector::Zero(n));
}

TEST(IoDevice, AFaultPutsTheSafeOutputsOnAndLatchesUntilCleared) {
  auto arm = test::makeArm();
  IoSafetyParams safety;
  safety.ramp_in_s = 0.0;
  SimIoDevice device(*arm, {}, safety);
  const int n = device.numJoints();
  device.configure();
  device.activate();
  ASSERT_TRUE(device.write(volts(n, 3.0)).ok());
  ASSERT_TRUE(device.write(volts(n, 3.0)).ok());
  EXPECT_EQ(device.appliedCommand()[2], 3.0);
  device.fault("test fault");
  EXPECT_EQ(device.state(), IoState::kFault);
  EXPECT_EQ(device.appliedCommand(), IoVector::Zero(n));  // immediately, not at the next write
  EXPECT_FALSE(device.write(volts(n, 3.0)).ok());
  EXPECT_EQ(device.appliedCommand(), IoVector::Zero(n));  // never "hold the last command"
  EXPECT_FALSE(device.enableAsserted());
  EXPECT_STREQ(device.status().message, "test fault");
  EXPECT_THROW(device.activate(), std::logic_error);
  device.clearFault();
  EXPECT_EQ(device.state(), IoState::kInactive);
  device.activate();
  ASSERT_TRUE(device.write(volts(n, 3.0)).ok());
  EXPECT_EQ(device.appliedCommand(), IoVector::Zero(n));
}

TEST(IoDevice, CommandsAreClampedAndANonFiniteCommandIsNull) {
  auto arm = test::makeArm();
  IoSafetyParams safety;
  safety.ramp_in_s = 0.0;
  safety.valve_limit_v = 6.0;
  SimIoDevice device(*arm, {}, safety);
  const int n = device.numJoints();
  device.configure();
  device.activate();
  ASSERT_TRUE(device.write(volts(n, 0.0)).ok());
  IoVector cmd = volts(n, 9.0);
  cmd[1] = -9.0;
  cmd[2] = std::numeric_limits<double>::quiet_NaN();
  ASSERT_TRUE(device.write(cmd).ok());
  EXPECT_EQ(device.appliedCommand()[0], 6.0);
  EXPECT_EQ(device.appliedCommand()[1], -6.0);
  EXPECT_EQ(device.appliedCommand()[2], 0.0);
}

TEST(SimIo, ReadingsAreTheConfiguredNumberOfPeriodsOld) {
  // Two identical arms, latency 0 and 2, driven by the same commands: the second reads what the
  // first read two periods earlier.
  auto arm0 = test::makeArm(0);
  auto arm2 = test::makeArm(2);
  IoSafetyParams safety;
  safety.ramp_in_s = 0.0;
  SimIoDevice d0(*arm0, {}, safety);
  SimIoDevice d2(*arm2, {}, safety);
  d0.configure();
  d2.configure();
  d0.activate();
  d2.activate();
  const int n = d0.numJoints();
  std::vector<JointSample> s0;
  for (int k = 0; k < 60; ++k) {
    JointSample a;
    JointSample b;
    ASSERT_TRUE(d0.read(a).ok());
    ASSERT_TRUE(d2.read(b).ok());
    s0.push_back(a);
    if (k >= 2) {
      EXPECT_EQ(b.q_rad, s0[static_cast<std::size_t>(k - 2)].q_rad) << "tick " << k;
      EXPECT_EQ(b.tau_load_cell_nm, s0[static_cast<std::size_t>(k - 2)].tau_load_cell_nm) << "tick " << k;
      EXPECT_NEAR(b.t_s, a.t_s - 2 * kPeriod_s, 1e-12);
    }
    IoVector cmd = IoVector::Zero(n);
    cmd[3] = 2.0 * std::sin(0.2 * k);
    ASSERT_TRUE(d0.write(cmd).ok());
    ASSERT_TRUE(d2.write(cmd).ok());
  }
}

TEST(SimIo, APositiveValveCommandMovesTheJointTowardPlusQ) {
  auto arm = test::makeArm(1);
  IoSafetyParams safety;
  safety.ramp_in_s = 0.0;
  SimIoDevice device(*arm, {}, safety);
  device.configure();
  device.activate();
  const int n = device.numJoints();
  JointSample first;
  ASSERT_TRUE(device.read(first).ok());
  JointSample s;
  for (int k = 0; k < 200; ++k) {
    IoVector cmd = IoVector::Zero(n);
    cmd[3] = 1.5;  // the elbow
    ASSERT_TRUE(device.write(cmd).ok());
    ASSERT_TRUE(device.read(s).ok());
  }
  EXPECT_GT(s.q_rad[3] - first.q_rad[3], 0.02);
  EXPECT_NEAR(s.t_s, 200 * kPeriod_s, 1e-9);  // one period per read, one period of latency
}

TEST(SimIo, ReadAndWriteDoNotAllocate) {
  auto arm = test::makeArm(1);
  SimIoDevice device(*arm, {}, {});
  device.configure();
  device.activate();
  const IoVector cmd = volts(device.numJoints(), 0.5);
  JointSample s;
  ASSERT_TRUE(device.read(s).ok());
  for (int k = 0; k < 50; ++k) {
    EXPECT_NO_HEAP_ALLOCATION(device.read(s));
    EXPECT_NO_HEAP_ALLOCATION(device.write(cmd));
  }
}

// The same with chamber pressure transducers on the elbow, read by sim itself, by sim through a
// channel map that wires them, and by the fake DAQ's comedi back-end.
TEST(SimIo, ReadingChamberPressuresDoesNotAllocate) {
  const plant::PlantConfig plant = test::plantWithElbowTransducers();
  const DaqConfig map = test::daqConfigWithElbowPressures();
  SimulatedArm own_arm(test::model(), plant, test::restPosture(), 1e-3, 1);
  SimulatedArm mapped_arm(test::model(), plant, test::restPosture(), 1e-3, 1);
  SimulatedArm board_arm(test::model(), plant, test::restPosture(), 1e-3, 1);
  SimIoOptions through_map;
  through_map.converters = &map;
  SimIoDevice own(own_arm, {}, {});
  SimIoDevice mapped(mapped_arm, through_map, {});
  FakeDaqBoard board(map);
  FakeDaqRig rig(board, board_arm, map, 0.05);
  std::unique_ptr<IoDevice> fake = makeFakeDaqIoDevice(map, test::model(), 1e-3, {}, &rig);
  for (IoDevice* device : {static_cast<IoDevice*>(&own), static_cast<IoDevice*>(&mapped), fake.get()}) {
    SCOPED_TRACE(std::string(device->name()));
    device->configure();
    device->activate();
    const IoVector cmd = volts(device->numJoints(), 0.5);
    JointSample s;
    ASSERT_TRUE(device->read(s).ok());
    for (int k = 0; k < 20; ++k) {
      EXPECT_NO_HEAP_ALLOCATION(device->read(s));
      EXPECT_NO_HEAP_ALLOCATION(device->write(cmd));
    }
    EXPECT_EQ(s.pressure_mask, 1u << 3);
    EXPECT_GT(s.p_a_pa[3], 0.0);
  }
}

}  // namespace
}  // namespace fullarm::hil
