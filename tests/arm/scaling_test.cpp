// Human arm size (paper section 3.2.3): scaled segment lengths checked by distances between
// joint origins, which do not depend on the configuration.

#include "fullarm/arm/arm_scaling.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "arm_test_util.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "scratch_dir.hpp"

namespace fullarm::arm {
namespace {

constexpr double kTol = 1e-12;

TEST(ArmScaling, SizeOfDefaultModel) {
  const ArmSize size = armSizeOf(test::defaultModel());
  EXPECT_DOUBLE_EQ(*size.upper_arm_length_m, 0.287);  // l2
  EXPECT_DOUBLE_EQ(*size.forearm_length_m, 0.2781);   // l4
  EXPECT_DOUBLE_EQ(*size.hand_length_m, 0.085);       // SL end-effector offset
}

TEST(ArmScaling, ScaledSegmentsHaveTheRequestedLengthsInEveryPosture) {
  const ArmModel& model = test::defaultModel();
  ArmSize size;
  size.upper_arm_length_m = 0.32;
  size.forearm_length_m = 0.25;
  size.hand_length_m = 0.10;
  size.link_radius_scale = 1.2;
  const ArmModel scaled = scaleArm(model, size);
  ArmData data(scaled);
  std::mt19937 rng(3);
  const int hr = scaled.jointIndex("R_HR");
  const int wr = scaled.jointIndex("R_WR");
  const int waa = scaled.jointIndex("R_WAA");
  for (int trial = 0; trial < 50; ++trial) {
    computeForwardKinematics(scaled, data, test::randomConfiguration(scaled, rng));
    const auto o = [&](int i) { return data.o_W[static_cast<std::size_t>(i)]; };
    // Shoulder (frame 2) to elbow-level frame 3: offset a2 = l1 and length d3.
    EXPECT_NEAR((o(hr) - o(hr - 1)).norm(), std::hypot(0.0381, 0.32), kTol);
    // Elbow frame 4 to wrist frame 5: alpha 90 deg, a 0, so the distance is d5.
    EXPECT_NEAR((o(wr) - o(wr - 1)).norm(), 0.25, kTol);
    EXPECT_NEAR((data.X_WT.translation() - o(waa)).norm(), 0.10, kTol);
    // The upper-arm capsule still runs from the shoulder point to the elbow-level origin.
    const Eigen::Vector3d top = pointInWorld(data, hr, scaled.joints[static_cast<std::size_t>(hr)].geometry.from_m);
    EXPECT_NEAR((top - o(hr)).norm(), 0.32, kTol);
  }
  EXPECT_DOUBLE_EQ(scaled.joints[static_cast<std::size_t>(hr)].geometry.radius_m, 0.05 * 1.2);
  // Centres of mass move with their segment: upper arm z by 0.32 / 0.287, hand by 0.10 / 0.085.
  EXPECT_NEAR(scaled.joints[static_cast<std::size_t>(hr)].inertial.com_m.z(), -0.188 * 0.32 / 0.287, kTol);
  EXPECT_NEAR(scaled.joints[static_cast<std::size_t>(waa)].inertial.com_m.x(), 0.05 * 0.10 / 0.085, kTol);
  // Hand joints on the hand link move with the hand; the thumb's second joint (on R_TL) does not.
  const auto origin = [](const ArmModel& m, const char* name) {
    return m.joints[static_cast<std::size_t>(m.jointIndex(name))].X_PL0.translation();
  };
  EXPECT_NEAR((origin(scaled, "R_FAA") - origin(model, "R_FAA") * 0.10 / 0.085).norm(), 0.0, kTol);
  EXPECT_NEAR((origin(scaled, "R_TL") - origin(model, "R_TL") * 0.10 / 0.085).norm(), 0.0, kTol);
  EXPECT_NEAR((origin(scaled, "R_TV") - origin(model, "R_TV")).norm(), 0.0, kTol);
  EXPECT_DOUBLE_EQ(scaled.totalMass(), model.totalMass());
}

TEST(ArmScaling, UnsetFieldsKeepTheModel) {
  const ArmModel& model = test::defaultModel();
  const ArmModel same = scaleArm(model, ArmSize{});
  for (std::size_t i = 0; i < model.joints.size(); ++i) {
    EXPECT_TRUE(same.joints[i].X_PL0.isApprox(model.joints[i].X_PL0, 0.0));
  }
}

TEST(ArmScaling, NonPositiveLengthIsRejectedWithItsKey) {
  ArmSize size;
  size.forearm_length_m = -0.2;
  try {
    (void)scaleArm(test::defaultModel(), size);
    FAIL() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "arm_size.forearm_length_m");
  }
}

TEST(ArmScaling, LoadsSizeFileAndRejectsUnknownKeys) {
  const std::filesystem::path dir = fullarm::test::scratchDir("fullarm_scaling_test");
  const auto good = dir / "size.yaml";
  std::ofstream(good) << "arm_size:\n  upper_arm_length_m: 0.30\n  hand_length_m: 0.09\n";
  const ArmSize size = loadArmSize(good);
  EXPECT_DOUBLE_EQ(*size.upper_arm_length_m, 0.30);
  EXPECT_FALSE(size.forearm_length_m.has_value());
  EXPECT_DOUBLE_EQ(*size.hand_length_m, 0.09);

  const auto bad = dir / "bad.yaml";
  std::ofstream(bad) << "arm_size:\n  upper_arm_lenght_m: 0.30\n";
  try {
    (void)loadArmSize(bad);
    FAIL() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "arm_size.upper_arm_lenght_m");
    EXPECT_EQ(e.file(), bad);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fullarm::arm
