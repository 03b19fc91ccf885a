#pragma once
/// @file
/// The linear checks of linear_analysis.hpp applied to a closed-loop scenario of
/// closed_loop.hpp, with the same joint, load, user impedance, wall, period and delay as the
/// nonlinear simulation, so that the two can be compared (`fullarm validate`, and the test that
/// gains at 80 % of the predicted stability limit are stable in the nonlinear simulation and
/// oscillate at 120 %). Offline (allocates), not @rt.

#include <string>
#include <vector>

#include "fullarm/design/closed_loop.hpp"
#include "fullarm/design/linear_analysis.hpp"

namespace fullarm::design {

/// Which linear results gate the verdict. Closed-loop stability (spectral radius < 1, free and
/// in contact, for every delay analysed) always does.
struct LinearRequirements {
  double max_peak_sensitivity = 1.7;   ///< Ms bound (docs/sources.md, Control 1: Ms <= 1.7 <=> GM >= 2.4, PM >= 34 deg)
  bool gate_peak_sensitivity = false;  ///< fail when Ms exceeds the bound
  bool gate_sector = false;            ///< fail when min Re L <= -1 (circle criterion for sat())
  bool gate_passivity = false;         ///< fail when min Re Z < 0 (the device is not passive)
};

/// The linear model of the scenario's joint: hydraulics, link inertia (the scenario's load
/// minus the user's inertia), gravity, and the user's inertia, stiffness and damping in joint
/// space.
[[nodiscard]] JointPlantModel scenarioPlantModel(const JointScenario& scenario);

/// Linear results of one scenario.
struct ScenarioLinearResult {
  LinearChecks free;     ///< at the end of the free move, no wall (with frequency data)
  LinearChecks contact;  ///< at the wall, the scenario's wall in contact (with frequency data)
  /// Spectral radius of the coupled closed loop for each analysed delay (1..max_delay), free
  /// and in contact.
  std::vector<int> delays;
  std::vector<double> free_spectral_radius;
  std::vector<double> contact_spectral_radius;
  /// Predicted stability limit: the largest factor on the controller's output gain (B_o/eps,
  /// or all PID gains) keeping both loops stable at the scenario's delay.
  double predicted_gain_limit = 0.0;
  std::vector<ZWidthPoint> z_width;  ///< largest stable wall stiffness vs wall damping
  bool pass = false;
  std::string reason;  ///< why not, when pass is false
};

/// Analyses the scenario at its delay (margins, Ms, sector, passivity, gain limit), the
/// stability for delays 1..`max_delay`, and the Z-width for `wall_dampings`.
/// @throws std::runtime_error if no trim exists; core::ConfigError for invalid gains.
[[nodiscard]] ScenarioLinearResult analyzeScenario(const JointScenario& scenario, const LinearRequirements& req,
                                                   int max_delay, const std::vector<double>& wall_dampings);

/// The scenario with its controller's output gain multiplied by `factor` (B_o/eps by dividing
/// eps, the PID by scaling kp, ki and kd), the factor of ScenarioLinearResult::predicted_gain_limit.
[[nodiscard]] JointScenario scaleControllerGain(const JointScenario& scenario, double factor);

}  // namespace fullarm::design
