// hil::IoBackend builds each back-end by name: sim and fakedaq serve the plant's and the channel
// map's joints and read the simulated arm it holds (the same first reading as a device built by
// hand on an arm of the same plant and seed); comedi without its board fails naming the device
// file; a missing plant or channel map is refused before anything is built.

#include <gtest/gtest.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "fullarm/hil/io_backend.hpp"
#include "fullarm/hil/sim_io.hpp"
#include "hil_fixture.hpp"

namespace fullarm::hil {
namespace {

IoBackendOptions optionsFor(IoKind kind) {
  IoBackendOptions o;
  o.io = kind;
  o.period_s = 1e-3;
  o.latency_samples = 1;
  o.plant = &test::plantConfig();
  o.posture = test::restPosture();
  o.daq = &test::daqConfig();
  return o;
}

TEST(IoBackend, NamesItsKinds) {
  EXPECT_STREQ(ioKindName(IoKind::kSim), "sim");
  EXPECT_STREQ(ioKindName(IoKind::kFakeDaq), "fakedaq");
  EXPECT_STREQ(ioKindName(IoKind::kComedi), "comedi");
  EXPECT_STREQ(ioKindName(IoKind::kLcm), "lcm");
}

TEST(IoBackend, SimReadsTheArmItHoldsAsADeviceBuiltByHand) {
  IoBackend backend(test::model(), optionsFor(IoKind::kSim));
  ASSERT_NE(backend.simulatedArm(), nullptr);
  EXPECT_EQ(backend.fakeBoard(), nullptr);
  EXPECT_EQ(backend.kind(), IoKind::kSim);
  EXPECT_EQ(backend.device().joints().modelIndices(), test::armJoints().modelIndices());

  SimulatedArm arm(test::model(), test::plantConfig(), test::restPosture(), 1e-3, 1);
  SimIoDevice by_hand(arm, {}, IoSafetyParams{});
  backend.device().configure();
  by_hand.configure();
  JointSample a;
  JointSample b;
  ASSERT_TRUE(backend.device().read(a).ok());
  ASSERT_TRUE(by_hand.read(b).ok());
  for (int k = 0; k < a.q_rad.size(); ++k) {
    EXPECT_EQ(a.q_rad[k], b.q_rad[k]) << k;
    EXPECT_EQ(a.tau_load_cell_nm[k], b.tau_load_cell_nm[k]) << k;
  }
}

TEST(IoBackend, FakeDaqServesTheChannelMapsJointsThroughItsBoard) {
  IoBackend backend(test::model(), optionsFor(IoKind::kFakeDaq));
  ASSERT_NE(backend.simulatedArm(), nullptr);
  ASSERT_NE(backend.fakeBoard(), nullptr);
  EXPECT_EQ(backend.fakeBoard()->device(), test::daqConfig().device);
  EXPECT_EQ(static_cast<std::size_t>(backend.device().numJoints()), test::daqConfig().joints.size());
  backend.device().configure();
  JointSample s;
  ASSERT_TRUE(backend.device().read(s).ok());
  // The elbow reads the posture's angle to within a few potentiometer counts (12 bits over the
  // joint's range: under 2 mrad a count).
  EXPECT_NEAR(s.q_rad[3], test::restPosture()[3], 0.01);
  EXPECT_EQ(backend.fakeBoard()->state().periods, 1u) << "one period passes per read";
}

TEST(IoBackend, ComediWithoutItsBoardNamesTheDeviceFile) {
  if (std::filesystem::exists(test::daqConfig().device)) GTEST_SKIP() << "a board is present";
  try {
    IoBackend backend(test::model(), optionsFor(IoKind::kComedi));
    EXPECT_EQ(backend.simulatedArm(), nullptr);
    backend.device().configure();
    FAIL() << "configured without a board";
  } catch (const DeviceError& e) {
    EXPECT_NE(std::string(e.what()).find(test::daqConfig().device), std::string::npos) << e.what();
  }
}

TEST(IoBackend, RefusesAMissingPlantOrChannelMap) {
  IoBackendOptions no_plant = optionsFor(IoKind::kSim);
  no_plant.plant = nullptr;
  EXPECT_THROW(IoBackend(test::model(), no_plant), std::invalid_argument);
  IoBackendOptions no_map = optionsFor(IoKind::kFakeDaq);
  no_map.daq = nullptr;
  EXPECT_THROW(IoBackend(test::model(), no_map), std::invalid_argument);
  IoBackendOptions converters = optionsFor(IoKind::kSim);
  converters.sim_uses_daq_converters = true;
  converters.daq = nullptr;
  EXPECT_THROW(IoBackend(test::model(), converters), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::hil
