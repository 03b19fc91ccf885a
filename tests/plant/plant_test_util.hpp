#pragma once
// Shared fixtures of the plant tests: hand-built joints with textbook-friendly parameters.

#include <cmath>
#include <ostream>
#include <vector>

#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/hydraulics.hpp"

namespace fullarm::plant {
/// Test names and messages print the integrator by name.
inline void PrintTo(IntegratorKind kind, std::ostream* os) {
  *os << (kind == IntegratorKind::kCvodes ? "cvodes" : kind == IntegratorKind::kRodas3 ? "rodas3" : "rodas4");
}
}  // namespace fullarm::plant

namespace fullarm::plant::test {

/// Named tolerances of the plant suites.
struct PlantTolerance {
  static constexpr double kNaturalFrequency = 0.03;  ///< natural frequency within 3 %
  static constexpr double kBuildUpRate = 0.03;       ///< pressure build-up within 3 %
  static constexpr double kNoLoadVelocity = 0.02;    ///< no-load velocity within 2 %
  static constexpr double kRigidBody = 1e-6;         ///< ideal-torque arm vs fullarm::arm, relative
  static constexpr double kRtolHalvingRms = 0.005;   ///< halving rtol changes the response < 0.5 % RMS
  static constexpr double kStopOvershootDeg = 0.5;   ///< hard stop exceeded by at most 0.5 deg
};

/// A symmetric rotary-vane joint of the worked example of docs/sources.md, Plant 1.6:
/// D = 2.5e-6 m^3/rad, V_t = 6e-6 m^3 at mid-stroke (q = 0), beta = 1e9 Pa, no air, no
/// leakage, no friction, range [-1, 1] rad, critically centred valve.
inline JointParams vaneJoint() {
  JointParams p;
  p.name = "test_vane";
  p.supply_pressure_pa = 20.7e6;
  p.return_pressure_pa = 0.3e6;
  p.min_rad = -1.0;
  p.max_rad = 1.0;
  p.actuator.kind = ActuatorKind::kRotaryVane;
  p.actuator.displacement_m3_per_rad = 2.5e-6;
  p.chambers.dead_volume_a_m3 = 0.5e-6;  // + D * 1 rad = 3e-6 at q = 0
  p.chambers.dead_volume_b_m3 = 0.5e-6;
  p.fluid.oil_bulk_modulus_pa = 1e9;
  p.fluid.air_fraction = 0.0;
  p.valve.natural_frequency_hz = 150.0;
  p.valve.damping_ratio = 0.7;
  p.valve.amplifier_gain_per_v = 0.1;
  p.valve.rated_flow_m3ps = 1e-5;
  p.valve.rated_pressure_drop_pa = 3.5e6;
  p.potentiometer = {4.4132e-4, 1023, 1, 0.0, 12};
  p.torque_sensor = {-0.02488643, -2047, 12};
  return p;
}

/// Stored energy of a closed chamber with constant bulk modulus: for p' = -beta V'/V the
/// storage function E = V beta (exp(p/beta) - 1 - p/beta) has dE/dt = -p dV/dt exactly
/// (derived in docs/plant.md; ~ V p^2 / (2 beta) for small p/beta).
inline double chamberEnergy(double volume_m3, double p_pa, double beta_pa) {
  const double u = p_pa / beta_pa;
  return volume_m3 * beta_pa * std::expm1(u) - volume_m3 * beta_pa * u;
}

}  // namespace fullarm::plant::test
