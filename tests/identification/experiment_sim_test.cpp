// The closed-loop experiment runner on the simulated DTS: the excitation moves the driven joint
// and the held joints stay at their holds.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>

#include "fullarm/hil/sim_io.hpp"
#include "fullarm/identification/experiment.hpp"
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

}  // namespace
}  // namespace fullarm::identification
