#pragma once
/// @file
/// Cylinder-on-lever geometry of the linear (hydraulic cylinder) actuators.
///
/// With moment arm r (joint axis to rod attachment), mount distance d (joint axis to the
/// cylinder's fixed mount) and lever angle phi = q + lever_angle_offset between them, the
/// law of cosines gives the cylinder length L(phi) = sqrt(r^2 + d^2 - 2 r d cos(phi)) and the
/// effective moment arm dL/dphi = r d sin(phi) / L, which equals r at phi = acos(r/d)
/// (docs/dts-reference.md §5).

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Cylinder length [m] at joint angle q [rad]. Requires a linear actuator.
/// @rt
[[nodiscard]] double cylinderLength(const ActuatorGeometry& act, double q_rad) noexcept;

/// Effective moment arm dL/dq [m] at q: joint torque = cylinder force * moment arm.
/// Requires a linear actuator.
/// @rt
[[nodiscard]] double actuatorMomentArm(const ActuatorGeometry& act, double q_rad) noexcept;

/// Joint angle [rad] where the moment arm is largest (the lever is perpendicular to the cylinder).
[[nodiscard]] double angleOfMaximumMomentArm(const ActuatorGeometry& act) noexcept;

}  // namespace fullarm::arm
