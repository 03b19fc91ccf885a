#pragma once
/// @file
/// Count <-> SI conversion of the potentiometers and joint torque sensors, following the
/// SL translation rule restated in reference sarcos-master-arm.md section 6.1.

#include <utility>

namespace fullarm::arm {

/// Potentiometer read through an ADC: q = polarity * (counts + offset_counts) * slope - joint_offset.
struct PotentiometerCalibration {
  double slope_rad_per_count = 0.0;
  double offset_counts = 0.0;
  int polarity = 1;
  double joint_offset_rad = 0.0;
  int bits = 12;
};

/// Joint torque sensor (load cell) read through an ADC: tau = (counts + offset_counts) * slope.
/// The same rule describes the desired-torque DAC (TorqueCommandCalibration).
struct TorqueSensorCalibration {
  double slope_nm_per_count = 0.0;
  double offset_counts = 0.0;
  int bits = 12;
};

/// The desired-torque DAC of a joint card: tau = (code + offset_counts) * slope. Its slope may
/// differ in sign from the load cell's (the DTS finger joints, reference section 6.1).
using TorqueCommandCalibration = TorqueSensorCalibration;

/// Largest ADC/DAC code for `bits` bits (4095 for 12 bits).
/// @rt
[[nodiscard]] constexpr int maxCode(int bits) noexcept {
  return (1 << bits) - 1;
}

/// Round to the nearest code and clamp to [0, maxCode(bits)] (ADC/DAC quantisation).
/// @rt
[[nodiscard]] int quantizeCode(double counts, int bits) noexcept;

/// Joint angle [rad] from potentiometer counts.
/// @rt
[[nodiscard]] double potentiometerAngle(const PotentiometerCalibration& cal, double counts) noexcept;

/// Potentiometer counts (unquantised) that read as joint angle q [rad].
/// @rt
[[nodiscard]] double potentiometerCounts(const PotentiometerCalibration& cal, double q_rad) noexcept;

/// Joint torque [N m] from torque-sensor counts.
/// @rt
[[nodiscard]] double torqueSensorTorque(const TorqueSensorCalibration& cal, double counts) noexcept;

/// Torque-sensor counts (unquantised) that read as torque tau [N m].
/// @rt
[[nodiscard]] double torqueSensorCounts(const TorqueSensorCalibration& cal, double tau_nm) noexcept;

/// Desired-torque DAC code for a torque command tau [N m], rounded and clamped to the DAC range
/// (a command beyond full scale saturates, as on the hardware).
/// @rt
[[nodiscard]] int torqueCommandCode(const TorqueCommandCalibration& cal, double tau_nm) noexcept;

/// Angle range [rad] the potentiometer can report over codes 0 .. maxCode (min, max).
[[nodiscard]] std::pair<double, double> potentiometerSpan(const PotentiometerCalibration& cal) noexcept;

/// Torque range [N m] the torque sensor can report over codes 0 .. maxCode (min, max).
[[nodiscard]] std::pair<double, double> torqueSensorSpan(const TorqueSensorCalibration& cal) noexcept;

/// Angle resolution [rad per count].
[[nodiscard]] double potentiometerResolution(const PotentiometerCalibration& cal) noexcept;

}  // namespace fullarm::arm
