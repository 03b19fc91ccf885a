// The closed-loop experiment runner on the simulated DTS: the excitation moves the driven joint
// and the held joints stay at their holds.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "fullarm/hil/sim_io.hpp"
#include "fullarm/identification/experiment.hpp"
#include "fullarm/identification/joint_groups.hpp"
#include "fullarm/plant/hydraulics.hpp"
#include "hil_fixture.hpp"

namespace fullarm::identification {
namespace {

constexpr double kT = 1.0e-3;

TEST(ExperimentTest, OnTheSimulatedArmTheExcitationMovesOnlyTheDrivenJoint) {
  auto arm = hil::test::makeArm(1);
  hil::SimIoDevice device(*arm, {}, hil::IoSafetyParams{0.2, 10.0});
  const int elbow = 3;
  const auto& limits = hil::test::model().joints[static_cast<std::size_t>(elbow)].limits;
  ExperimentOptions options;
  options.joint = elbow;
  options.settle_s = 0.5;
  options.min_rad = limits.min_rad;
  options.max_rad = limits.max_rad;
  const SampledSignal r = linearChirp(0.3, 0.5, 20.0, 2.0, kT);
  const ExperimentResult result = runExperiment(device, r, options);
  ASSERT_TRUE(result.completed) << result.stop_reason;
  EXPECT_EQ(device.state(), hil::IoState::kInactive);
  const auto& q = result.log.column("q_rad");
  double lo = q.front(), hi = q.front();
  for (double v : q) {
    lo = std::min(lo, v);
    hi = std::max(hi, v);
  }
  std::printf("driven joint range %.4f rad\n", hi - lo);
  EXPECT_GT(hi - lo, 0.005) << "the excitation did not move the joint";
  EXPECT_LT(hi - lo, 0.5);
  const Eigen::VectorXd& q_true = arm->trueConfiguration();
  for (int k = 0; k < 7; ++k) {
    if (k == elbow) continue;
    EXPECT_NEAR(q_true[k], result.hold_rad[static_cast<std::size_t>(k)], options.held_drift_limit_rad) << "joint " << k;
  }
}

// A joint with chamber pressure transducers: the sim back-end reads them, the log carries them
// after the five columns, and the hydraulic torque they give (hydraulicTorque) is the plant's
// own at the last reading (no latency; 16-bit transducers without noise: within a count). Through
// a DAQ channel map that wires no pressure channels, the same joint's pressures are not read.
TEST(ExperimentTest, ChamberPressuresAreLoggedWhereTheBackEndReadsThem) {
  plant::PlantConfig config = hil::test::plantConfig();
  plant::JointParams elbow = config.joints[3];
  elbow.sensor_noise.pressure_full_scale_pa = 25.0e6;
  elbow.sensor_noise.pressure_bits = 16;
  elbow.sensor_noise.pressure_noise_pa = 0.0;
  config.joints = {elbow};
  hil::SimulatedArm arm(hil::test::model(), config, hil::test::restPosture(), kT, 0);
  hil::SimIoDevice device(arm, {}, hil::IoSafetyParams{0.2, 10.0});
  ExperimentOptions options;
  options.joint = 0;
  options.settle_s = 0.3;
  options.min_rad = elbow.min_rad;
  options.max_rad = elbow.max_rad;
  const ExperimentResult result = runExperiment(device, linearChirp(0.5, 0.5, 20.0, 1.0, kT), options);
  ASSERT_TRUE(result.completed) << result.stop_reason;
  ASSERT_EQ(result.log.names.size(), kExperimentColumns.size() + 2);
  EXPECT_EQ(result.log.names[5], "pressure_a_pa");
  EXPECT_EQ(result.log.names[6], "pressure_b_pa");
  const std::vector<double> tau_h = hydraulicTorque(
      elbow, result.log.column("q_rad"), result.log.column("pressure_a_pa"), result.log.column("pressure_b_pa"));
  const plant::ChamberVolumes v =
      plant::chamberVolumes(elbow, plant::strokeRange(elbow), result.log.column("q_rad").back());
  const double count_nm = 25.0e6 / 65535.0 * (std::abs(v.dva_dq) + std::abs(v.dvb_dq));
  const double potentiometer_nm = 1e-3 * std::abs(arm.plant().hydraulicTorque(0));  // the angle's quantisation
  EXPECT_NEAR(tau_h.back(), arm.plant().hydraulicTorque(0), count_nm + potentiometer_nm);
  // It holds the link: on average the load cell's reading plus the friction at rest.
  double gap = 0.0;
  const auto& cell = result.log.column("tau_measured_nm");
  for (std::size_t k = 0; k < tau_h.size(); ++k) gap += tau_h[k] - cell[k];
  EXPECT_LT(std::abs(gap / static_cast<double>(tau_h.size())), 2.0 * elbow.friction.static_nm);

  hil::SimulatedArm mapped_arm(hil::test::model(), config, hil::test::restPosture(), kT, 0);
  hil::DaqConfig map = hil::test::daqConfig();
  map.joints = {map.joints[3]};
  hil::SimIoOptions mapped;
  mapped.converters = &map;
  hil::SimIoDevice through_map(mapped_arm, mapped, hil::IoSafetyParams{0.2, 10.0});
  const ExperimentResult no_pressures = runExperiment(through_map, linearChirp(0.5, 0.5, 20.0, 0.2, kT), options);
  ASSERT_TRUE(no_pressures.completed) << no_pressures.stop_reason;
  EXPECT_EQ(no_pressures.log.names, kExperimentColumns);
}

}  // namespace
}  // namespace fullarm::identification
