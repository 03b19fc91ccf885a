#include "fullarm/arm/actuator.hpp"

#include <cassert>
#include <cmath>

namespace fullarm::arm {

// A1: cylinder length and moment arm (law of cosines) (reports/equations.md).
double cylinderLength(const ActuatorGeometry& act, double q_rad) noexcept {
  assert(act.type == ActuatorGeometry::Type::kLinear);
  const double r = act.moment_arm_m;
  const double d = act.mount_distance_m;
  const double phi = q_rad + act.lever_angle_offset_rad;
  // Law of cosines in the triangle joint axis - rod attachment - cylinder mount.
  return std::sqrt(r * r + d * d - 2.0 * r * d * std::cos(phi));
}

// A1: cylinder length and moment arm (law of cosines) (reports/equations.md).
double actuatorMomentArm(const ActuatorGeometry& act, double q_rad) noexcept {
  const double phi = q_rad + act.lever_angle_offset_rad;
  // dL/dphi: virtual work of the cylinder force equals the joint torque.
  return act.moment_arm_m * act.mount_distance_m * std::sin(phi) / cylinderLength(act, q_rad);
}

double angleOfMaximumMomentArm(const ActuatorGeometry& act) noexcept {
  return std::acos(act.moment_arm_m / act.mount_distance_m) - act.lever_angle_offset_rad;
}

}  // namespace fullarm::arm
