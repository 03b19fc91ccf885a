// Sensor calibration and cylinder-on-lever geometry against the reference figures and the
// virtual-work identity (moment arm = dL/dq).

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "arm_test_util.hpp"
#include "fullarm/arm/actuator.hpp"
#include "fullarm/arm/sensors.hpp"

namespace fullarm::arm {
namespace {

const Joint& joint(const char* name) {
  const ArmModel& model = test::defaultModel();
  return model.joints[static_cast<std::size_t>(model.jointIndex(name))];
}

TEST(Sensors, PotentiometerRoundTripAndQuantisation) {
  for (const Joint& j : test::defaultModel().joints) {
    SCOPED_TRACE(j.name);
    const PotentiometerCalibration& cal = j.potentiometer;
    for (const double q : {j.limits.min_rad, j.default_rad, j.limits.max_rad}) {
      EXPECT_NEAR(potentiometerAngle(cal, potentiometerCounts(cal, q)), q, 1e-12);
      // One 12-bit reading is within half a count of the angle.
      const int code = quantizeCode(potentiometerCounts(cal, q), cal.bits);
      EXPECT_LE(std::abs(potentiometerAngle(cal, code) - q), 0.5 * potentiometerResolution(cal) + 1e-15);
    }
  }
}

// Reference section 6.1: resolution 0.023 deg/count (WAA) to 0.046 deg/count (WR).
TEST(Sensors, ResolutionMatchesReference) {
  constexpr double kDeg = 180.0 / std::numbers::pi;
  EXPECT_NEAR(potentiometerResolution(joint("R_WAA").potentiometer) * kDeg, 0.023, 0.0005);
  EXPECT_NEAR(potentiometerResolution(joint("R_WR").potentiometer) * kDeg, 0.046, 0.0005);
}

// Reference section 6.1: torque full scale 99.6, 50.9, 22.6 and 7.25 N m (2047 |slope|).
TEST(Sensors, TorqueFullScaleMatchesReference) {
  const auto full_scale = [](const char* name) {
    const auto [lo, hi] = torqueSensorSpan(joint(name).torque_sensor);
    return std::min(-lo, hi);
  };
  EXPECT_NEAR(full_scale("R_SFE"), 99.6, 0.05);
  EXPECT_NEAR(full_scale("R_EB"), 50.9, 0.05);
  EXPECT_NEAR(full_scale("R_WFE"), 22.6, 0.05);
  EXPECT_NEAR(full_scale("R_TV"), 7.25, 0.01);
}

TEST(Sensors, QuantizeClampsAndRounds) {
  EXPECT_EQ(quantizeCode(-3.0, 12), 0);
  EXPECT_EQ(quantizeCode(5000.0, 12), 4095);
  EXPECT_EQ(quantizeCode(10.4, 12), 10);
  EXPECT_EQ(quantizeCode(10.6, 12), 11);
  EXPECT_EQ(quantizeCode(std::nan(""), 12), 0);
  EXPECT_EQ(maxCode(16), 65535);
}

TEST(Sensors, TorqueRoundTrip) {
  const TorqueSensorCalibration& cal = joint("R_SAA").torque_sensor;
  for (const double tau : {-50.0, 0.0, 12.5, 99.0}) {
    EXPECT_NEAR(torqueSensorTorque(cal, torqueSensorCounts(cal, tau)), tau, 1e-12);
  }
  // Mid-scale code 2047 reads as zero torque (reference section 6.1).
  EXPECT_DOUBLE_EQ(torqueSensorTorque(cal, 2047.0), 0.0);
}

// Reference 6.1: the finger cards command torque with the opposite sign of their load cells;
// SL writes code = tau / des_slope + 2047, clipped to 0 .. 4095.
TEST(Sensors, TorqueCommandCodesFollowTheDacCalibration) {
  const Joint& eb = joint("R_EB");
  const Joint& tv = joint("R_TV");
  EXPECT_EQ(torqueCommandCode(eb.torque_command, 0.0), 2047);
  EXPECT_EQ(torqueCommandCode(eb.torque_command, 10.0), static_cast<int>(std::lround(10.0 / -0.02488643 + 2047)));
  // Same torque, opposite direction of the code on a finger: the sign anomaly.
  // R_TV: load slope +0.0035394, command slope -0.0035394 N m per count.
  EXPECT_GT(torqueSensorCounts(tv.torque_sensor, 1.0), 2047.0);
  EXPECT_LT(torqueCommandCode(tv.torque_command, 1.0), 2047);
  EXPECT_EQ(torqueCommandCode(tv.torque_command, 1.0), static_cast<int>(std::lround(1.0 / -0.0035394 + 2047)));
  // Beyond full scale the DAC saturates.
  EXPECT_EQ(torqueCommandCode(eb.torque_command, 500.0), 0);
  EXPECT_EQ(torqueCommandCode(eb.torque_command, -500.0), 4095);
}

TEST(Actuator, MomentArmIsTheDerivativeOfCylinderLength) {
  for (const Joint& j : test::defaultModel().joints) {
    if (j.actuator.type != ActuatorGeometry::Type::kLinear) continue;
    SCOPED_TRACE(j.name);
    constexpr double kStep = 1e-6;
    for (double q = j.limits.min_rad; q <= j.limits.max_rad; q += 0.05) {
      const double fd = (cylinderLength(j.actuator, q + kStep) - cylinderLength(j.actuator, q - kStep)) / (2 * kStep);
      EXPECT_NEAR(actuatorMomentArm(j.actuator, q), fd, 1e-9);
    }
  }
}

// Reference section 5: the largest moment arm is r, reached at q = 0.34 (SFE), -0.35 (SAA),
// 1.41 (EB), 0.15 (WFE) and 0.06 rad (WAA); the cylinder is then sqrt(d^2 - r^2) long.
TEST(Actuator, MaximumMomentArmMatchesReference) {
  const std::pair<const char*, double> expected[] = {
      {"R_SFE", 0.34}, {"R_SAA", -0.35}, {"R_EB", 1.41}, {"R_WFE", 0.15}, {"R_WAA", 0.06}};
  for (const auto& [name, q_expected] : expected) {
    SCOPED_TRACE(name);
    const ActuatorGeometry& act = joint(name).actuator;
    const double q_max = angleOfMaximumMomentArm(act);
    EXPECT_NEAR(q_max, q_expected, 0.01);
    EXPECT_NEAR(actuatorMomentArm(act, q_max), act.moment_arm_m, 1e-12);
    EXPECT_LT(actuatorMomentArm(act, q_max + 0.2), act.moment_arm_m);
    EXPECT_LT(actuatorMomentArm(act, q_max - 0.2), act.moment_arm_m);
    const double r = act.moment_arm_m;
    const double d = act.mount_distance_m;
    EXPECT_NEAR(cylinderLength(act, q_max), std::sqrt(d * d - r * r), 1e-12);
  }
}

}  // namespace
}  // namespace fullarm::arm
