// The closed-loop experiment on the fake DAQ (the comedi back-end on the simulated DTS, built by
// hil::IoBackend as `fullarm run` builds it): a device fault injected mid-experiment and a joint
// driven into its limit margin both stop the experiment with the valve amplifiers' codes at
// 0 V, the enable line no longer toggling, and the log ending at the stop. Chamber pressures
// wired through the channel map are logged as the sim back-end reads them.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "fullarm/hil/io_backend.hpp"
#include "fullarm/identification/experiment.hpp"
#include "hil_fixture.hpp"

namespace fullarm::identification {
namespace {

constexpr int kElbow = 3;  // device order of R_EB in the channel map

struct FakeDaqSetup {
  plant::PlantConfig plant = hil::test::plantConfig();
  std::unique_ptr<hil::IoBackend> backend;

  FakeDaqSetup() {
    hil::IoBackendOptions o;
    o.io = hil::IoKind::kFakeDaq;
    o.period_s = 1e-3;
    o.latency_samples = 1;
    o.safety = hil::IoSafetyParams{0.05, 10.0};
    o.plant = &plant;
    o.posture = hil::test::restPosture();
    o.daq = &hil::test::daqConfig();
    backend = std::make_unique<hil::IoBackend>(hil::test::model(), o);
  }
  hil::IoDevice& device() { return backend->device(); }
  // The volts the board's analog output of `joint`'s valve holds.
  double valveVolts(int joint) {
    const hil::DaqConfig& map = hil::test::daqConfig();
    const hil::FakeDaqState& s = backend->fakeBoard()->state();
    const auto channel = static_cast<std::size_t>(map.joints[static_cast<std::size_t>(joint)].valve.channel);
    return hil::codeToVolts(s.ao_codes[channel], s.ao, false);
  }
};

SampledSignal constant(double value_v, double duration_s) {
  SampledSignal s;
  s.sample_period_s = 1e-3;
  const auto n = static_cast<std::size_t>(std::llround(duration_s / s.sample_period_s));
  for (std::size_t k = 0; k < n; ++k) {
    s.time_s.push_back(static_cast<double>(k) * s.sample_period_s);
    s.value_v.push_back(value_v);
  }
  return s;
}

// Half a step of the 16-bit +-10 V output converter: the code of 0 V.
constexpr double kHalfOutputStep_v = 0.5 * 20.0 / 65535.0;

TEST(ExperimentFakeDaq, InjectedDeviceFaultStopsWithTheValvesAtNull) {
  FakeDaqSetup rig;
  const auto& map = hil::test::daqConfig();
  ASSERT_EQ(map.joints[kElbow].name, "R_EB");
  ExperimentOptions options;
  options.joint = kElbow;
  options.min_rad = 0.2;
  options.max_rad = 2.2;
  options.settle_s = 0.1;
  options.log_control_time = true;
  int reads = 0;
  double volts_before_fault = 0.0;
  // 0.3 s into the run (0.2 s into the excitation) the device is put in its fault state.
  options.before_read = [&] {
    if (++reads == 300) {
      volts_before_fault = rig.valveVolts(kElbow);
      rig.device().fault("injected fault");
    }
    return true;
  };
  const ExperimentResult r = runExperiment(rig.device(), constant(0.4, 1.0), options);
  EXPECT_FALSE(r.completed);
  std::printf("stopped after %zu samples: %s\n", r.log.rows(), r.stop_reason.c_str());
  EXPECT_NE(r.stop_reason.find("device"), std::string::npos) << r.stop_reason;
  // The log stops at the fault: about 200 samples of the 1,000.
  EXPECT_GT(r.log.rows(), 150u);
  EXPECT_LT(r.log.rows(), 250u);
  // The board's readings carry the wall clock; the log's time is the control time, uniform.
  const std::vector<double>& t = r.log.columns[0];
  for (std::size_t k = 1; k < t.size(); ++k) ASSERT_NEAR(t[k] - t[k - 1], 1e-3, 1e-9) << k;
  // Before the fault the valve carried the hold plus the excitation; after it, null.
  EXPECT_GT(std::abs(volts_before_fault), 0.1);
  for (int k = 0; k < rig.device().numJoints(); ++k) EXPECT_LE(std::abs(rig.valveVolts(k)), kHalfOutputStep_v) << k;
  const std::uint64_t changes = rig.backend->fakeBoard()->state().enable_changes;
  hil::JointSample sample;
  (void)rig.device().read(sample);
  (void)rig.device().write(hil::IoVector::Constant(rig.device().numJoints(), 1.0));
  EXPECT_EQ(rig.backend->fakeBoard()->state().enable_changes, changes) << "enable line toggled after the stop";
  EXPECT_LE(std::abs(rig.valveVolts(kElbow)), kHalfOutputStep_v);
}

TEST(ExperimentFakeDaq, JointDrivenIntoItsLimitMarginStopsWithTheValvesAtNull) {
  FakeDaqSetup rig;
  hil::JointSample start;
  rig.device().configure();
  ASSERT_TRUE(rig.device().read(start).ok());
  ExperimentOptions options;
  options.joint = kElbow;
  // An upper limit 0.08 rad above the start, margin 0.05: 0.03 rad of room, which a constant
  // 2 V on the valve crosses within the excitation.
  options.min_rad = start.q_rad[kElbow] - 1.0;
  options.max_rad = start.q_rad[kElbow] + 0.08;
  options.settle_s = 0.1;
  const ExperimentResult r = runExperiment(rig.device(), constant(2.0, 2.0), options);
  ASSERT_FALSE(r.completed);
  std::printf("stopped after %zu samples: %s\n", r.log.rows(), r.stop_reason.c_str());
  EXPECT_NE(r.stop_reason.find("limits"), std::string::npos) << r.stop_reason;
  ASSERT_GT(r.log.rows(), 0u);
  // The last logged angle is inside the margin; the stop came before the limit itself.
  EXPECT_LE(r.log.columns[3].back(), options.max_rad - options.limit_margin_rad);
  EXPECT_GT(r.log.columns[3].back(), start.q_rad[kElbow]);
  for (int k = 0; k < rig.device().numJoints(); ++k) EXPECT_LE(std::abs(rig.valveVolts(k)), kHalfOutputStep_v) << k;
  EXPECT_EQ(rig.device().state(), hil::IoState::kInactive);
}

TEST(ExperimentFakeDaq, PacingOverrunStopsBeforeTheLateReadWithTheValvesAtNull) {
  FakeDaqSetup rig;
  ExperimentOptions options;
  options.joint = kElbow;
  options.min_rad = 0.2;
  options.max_rad = 2.2;
  options.settle_s = 0.1;
  options.log_control_time = true;
  int reads = 0;
  // The pacing reports a missed period on the 250th read (0.15 s into the excitation).
  options.before_read = [&] { return ++reads != 250; };
  const ExperimentResult r = runExperiment(rig.device(), constant(0.4, 1.0), options);
  ASSERT_FALSE(r.completed);
  EXPECT_NE(r.stop_reason.find("pacing overrun"), std::string::npos) << r.stop_reason;
  // Reads 1 (before activation, serving period 0) .. 249 (period 248) were taken: 249 control
  // periods, the first 100 settling, 149 logged.
  EXPECT_EQ(r.log.rows(), 149u);
  EXPECT_EQ(reads, 250);
  for (int k = 0; k < rig.device().numJoints(); ++k) EXPECT_LE(std::abs(rig.valveVolts(k)), kHalfOutputStep_v) << k;
  EXPECT_EQ(rig.device().state(), hil::IoState::kInactive);
  // A pacing that misses its first period: nothing moves, the error says why.
  FakeDaqSetup rig2;
  options.before_read = [] { return false; };
  try {
    (void)runExperiment(rig2.device(), constant(0.4, 1.0), options);
    FAIL() << "a run whose first read is late must not start";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("pacing overrun"), std::string::npos) << e.what();
  }
  EXPECT_NE(rig2.device().state(), hil::IoState::kActive);
}

// The elbow's chamber pressures wired through the channel map (0-10 V for 0-25 MPa on inputs 7
// and 15): the experiment on the fake DAQ logs them, bit for bit as the sim back-end through the
// same map's converters, and within half a converter code of the sim back-end's readings of the
// plant's own 16-bit transducers. The map's count rules read the angle and the torque exactly as
// the plant does, so the three runs follow one trajectory.
TEST(ExperimentFakeDaq, ChamberPressuresWiredThroughTheChannelMapAreLogged) {
  const plant::PlantConfig plant = hil::test::plantWithElbowTransducers();
  const hil::DaqConfig map = hil::test::daqConfigWithElbowPressures();
  const auto run = [&](hil::IoKind io, bool through_map) {
    hil::IoBackendOptions o;
    o.io = io;
    o.safety = hil::IoSafetyParams{0.2, 10.0};
    o.plant = &plant;
    o.posture = hil::test::restPosture();
    o.daq = &map;
    o.sim_uses_daq_converters = through_map;
    hil::IoBackend backend(hil::test::model(), o);
    ExperimentOptions options;
    options.joint = kElbow;
    options.min_rad = 0.2;
    options.max_rad = 2.2;
    options.settle_s = 0.3;
    options.log_control_time = true;
    return runExperiment(backend.device(), linearChirp(0.5, 0.5, 20.0, 1.0, 1e-3), options);
  };
  const ExperimentResult fake = run(hil::IoKind::kFakeDaq, true);
  const ExperimentResult mapped = run(hil::IoKind::kSim, true);
  const ExperimentResult own = run(hil::IoKind::kSim, false);
  for (const ExperimentResult* r : {&fake, &mapped, &own}) {
    ASSERT_TRUE(r->completed) << r->stop_reason;
    ASSERT_EQ(r->log.names.size(), kExperimentColumns.size() + 2);
    EXPECT_EQ(r->log.names[5], "pressure_a_pa");
    EXPECT_EQ(r->log.names[6], "pressure_b_pa");
  }
  ASSERT_EQ(fake.log.rows(), mapped.log.rows());
  ASSERT_EQ(fake.log.rows(), own.log.rows());
  // Every column but the time (the board's readings carry the wall clock, the sim's the plant's).
  for (std::size_t c = 1; c < fake.log.names.size(); ++c) {
    EXPECT_EQ(fake.log.columns[c], mapped.log.columns[c]) << fake.log.names[c];
  }
  EXPECT_EQ(own.log.column("q_rad"), mapped.log.column("q_rad"));
  EXPECT_EQ(own.log.column("tau_measured_nm"), mapped.log.column("tau_measured_nm"));
  const double half_code_pa = hil::test::kElbowPressureHalfCodePa;
  double moved_pa = 0.0;
  for (const char* name : {"pressure_a_pa", "pressure_b_pa"}) {
    const std::vector<double>& through = mapped.log.column(name);
    const std::vector<double>& plant_own = own.log.column(name);
    for (std::size_t k = 0; k < through.size(); ++k) {
      ASSERT_NEAR(through[k], plant_own[k], half_code_pa) << name << " sample " << k;
      moved_pa = std::max(moved_pa, std::abs(plant_own[k] - plant_own.front()));
    }
  }
  EXPECT_GT(moved_pa, 20.0 * half_code_pa) << "the excitation did not move the pressures";
}

}  // namespace
}  // namespace fullarm::identification
