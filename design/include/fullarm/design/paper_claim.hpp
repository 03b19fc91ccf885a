#pragma once
/// @file
/// Measuring the DTS paper's claim (§3.3, last paragraph) with the closed-loop simulation of
/// closed_loop.hpp, not assuming it: "in the case of the simple torque controller there can be a
/// large spike in the command signal as the joint begins to move; this spike is significantly
/// reduced in the case of the admittance controller ... [which] allows higher controller gains
/// ... and stiffer virtual environments".
///
/// Method, per joint:
///  1. Run the admittance controller on the scenario; its RMS user torque over the free move is
///     the transparency target.
///  2. Scale the torque PID's gains (kp, ki, kd together; ratios from the gains file) by a
///     factor found on a log grid then by bisection, among the runs that are stable, so that the
///     PID's RMS user torque equals the target (equal free-space transparency). When no stable
///     scale reaches the target, the most transparent stable scale is used and `matched` is
///     false.
///  3. For both controllers at those gains: the onset spike (peak valve command and peak user
///     torque in the first 0.1 s of the free move, peak user torque over the free move) and the
///     largest stable wall stiffness (largestStableWall()).

#include <string>

#include "fullarm/design/closed_loop.hpp"

namespace fullarm::design {

/// Figures of one controller at the compared gains.
struct ControllerFigures {
  double free_rms_user_torque_nm = 0.0;
  double free_peak_user_torque_nm = 0.0;
  double onset_peak_valve_v = 0.0;
  double max_stable_wall_nm_per_rad = 0.0;  ///< from largestStableWall()
  bool stable_at_nominal_wall = false;
};

/// Result of measurePaperClaim().
struct PaperClaimResult {
  std::string joint_name;
  ControllerFigures admittance;
  ControllerFigures torque_pid;
  double pid_gain_scale = 1.0;   ///< factor on the file's PID gains that matches the transparency
  double pid_kp_v_per_nm = 0.0;  ///< the matched kp
  bool matched = false;          ///< |RMS_pid / RMS_adm - 1| <= tolerance
  int simulations = 0;
};

/// Settings of the search.
struct PaperClaimOptions {
  double transparency_tolerance = 0.02;  ///< relative RMS mismatch accepted
  double pid_scale_min = 0.02;
  double pid_scale_max = 20.0;
  int pid_grid_points = 13;
  int bisection_steps = 8;
  double wall_min_nm_per_rad = 100.0;  ///< softer walls let the push reach the joint's hard stop
  double wall_max_nm_per_rad = 1.0e5;
};

/// Largest wall stiffness K_w in [k_min, k_max] that the controller renders: simulateJoint() is
/// stable and, over the last contact window, the wall carries at least half of the user's push
/// (an arm that never reaches the wall renders nothing, however stiff). Wall damping as in
/// `scenario`; bisection in log K_w (`steps` halvings). Returns k_max if rendered there, 0 if not
/// at k_min. `simulations` (optional) counts the runs.
[[nodiscard]] double largestStableWall(JointScenario scenario, double k_min, double k_max, int steps,
                                       int* simulations = nullptr);

/// The comparison of the file comment on `scenario` (its gains hold both controllers' gains;
/// its `kind` is ignored).
[[nodiscard]] PaperClaimResult measurePaperClaim(const JointScenario& scenario, const PaperClaimOptions& options = {});

}  // namespace fullarm::design
