#include "fullarm/arm/sensors.hpp"

#include <algorithm>
#include <cmath>

namespace fullarm::arm {

int quantizeCode(double counts, int bits) noexcept {
  const double top = static_cast<double>(maxCode(bits));
  if (!(counts == counts)) return 0;  // NaN reads as code 0, like a disconnected input
  return static_cast<int>(std::lround(std::clamp(counts, 0.0, top)));
}

// S1: sensor count conversions (reports/equations.md).
double potentiometerAngle(const PotentiometerCalibration& cal, double counts) noexcept {
  return cal.polarity * (counts + cal.offset_counts) * cal.slope_rad_per_count - cal.joint_offset_rad;
}

double potentiometerCounts(const PotentiometerCalibration& cal, double q_rad) noexcept {
  return (q_rad + cal.joint_offset_rad) / (cal.polarity * cal.slope_rad_per_count) - cal.offset_counts;
}

// S1: sensor count conversions (reports/equations.md).
double torqueSensorTorque(const TorqueSensorCalibration& cal, double counts) noexcept {
  return (counts + cal.offset_counts) * cal.slope_nm_per_count;
}

double torqueSensorCounts(const TorqueSensorCalibration& cal, double tau_nm) noexcept {
  return tau_nm / cal.slope_nm_per_count - cal.offset_counts;
}

// S1: sensor count conversions (reports/equations.md).
int torqueCommandCode(const TorqueCommandCalibration& cal, double tau_nm) noexcept {
  return quantizeCode(torqueSensorCounts(cal, tau_nm), cal.bits);
}

std::pair<double, double> potentiometerSpan(const PotentiometerCalibration& cal) noexcept {
  const double a = potentiometerAngle(cal, 0.0);
  const double b = potentiometerAngle(cal, maxCode(cal.bits));
  return {std::min(a, b), std::max(a, b)};
}

std::pair<double, double> torqueSensorSpan(const TorqueSensorCalibration& cal) noexcept {
  const double a = torqueSensorTorque(cal, 0.0);
  const double b = torqueSensorTorque(cal, maxCode(cal.bits));
  return {std::min(a, b), std::max(a, b)};
}

double potentiometerResolution(const PotentiometerCalibration& cal) noexcept {
  return std::abs(cal.slope_rad_per_count);
}

}  // namespace fullarm::arm
