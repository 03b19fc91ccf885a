#include "fullarm/design/paper_claim.hpp"

#include <cmath>
#include <vector>

namespace fullarm::design {
namespace {

JointScenario withPidScale(const JointScenario& base, double scale) {
  JointScenario sc = base;
  sc.kind = controllers::ControllerKind::kTorquePid;
  sc.gains.torque_pid.kp_v_per_nm *= scale;
  sc.gains.torque_pid.ki_v_per_nms *= scale;
  sc.gains.torque_pid.kd_vs_per_nm *= scale;
  return sc;
}

ControllerFigures figures(const ClosedLoopResult& r) {
  ControllerFigures f;
  f.free_rms_user_torque_nm = r.free_rms_user_torque_nm;
  f.free_peak_user_torque_nm = r.free_peak_user_torque_nm;
  f.onset_peak_valve_v = r.onset_peak_valve_v;
  f.stable_at_nominal_wall = r.stable;
  return f;
}

}  // namespace

double largestStableWall(JointScenario scenario, double k_min, double k_max, int steps, int* simulations) {
  auto stableAt = [&](double k) {
    scenario.wall.enabled = true;
    scenario.wall.stiffness_nm_per_rad = k;
    if (simulations != nullptr) ++*simulations;
    const ClosedLoopResult r = simulateJoint(scenario);
    // Rendered: stable, and the wall carries the user's push (an arm that never reaches the
    // wall renders nothing, however stiff).
    return r.stable && r.wall_reached;
  };
  if (!stableAt(k_min)) return 0.0;
  if (stableAt(k_max)) return k_max;
  double lo = std::log(k_min), hi = std::log(k_max);
  for (int i = 0; i < steps; ++i) {
    const double mid = 0.5 * (lo + hi);
    if (stableAt(std::exp(mid))) {
      lo = mid;
    } else {
      hi = mid;
    }
  }
  return std::exp(lo);
}

PaperClaimResult measurePaperClaim(const JointScenario& scenario, const PaperClaimOptions& options) {
  PaperClaimResult out;
  out.joint_name = scenario.joint_name;
  JointScenario adm = scenario;
  adm.kind = controllers::ControllerKind::kAdmittance;
  const ClosedLoopResult adm_run = simulateJoint(adm);
  ++out.simulations;
  out.admittance = figures(adm_run);
  const double target = adm_run.free_rms_user_torque_nm;

  // Log grid of PID gain scales.
  struct Sample {
    double log_scale;
    ClosedLoopResult result;
  };
  std::vector<Sample> grid;
  const double l0 = std::log(options.pid_scale_min), l1 = std::log(options.pid_scale_max);
  for (int i = 0; i < options.pid_grid_points; ++i) {
    const double ls = l0 + (l1 - l0) * i / std::max(1, options.pid_grid_points - 1);
    grid.push_back({ls, simulateJoint(withPidScale(scenario, std::exp(ls)))});
    ++out.simulations;
  }
  auto mismatch = [&](const ClosedLoopResult& r) { return std::abs(std::log(r.free_rms_user_torque_nm / target)); };
  // Best stable grid point, then bisection inside a stable bracket around the target.
  int best = -1;
  for (int i = 0; i < static_cast<int>(grid.size()); ++i) {
    if (!grid[static_cast<std::size_t>(i)].result.stable) continue;
    if (best < 0 ||
        mismatch(grid[static_cast<std::size_t>(i)].result) < mismatch(grid[static_cast<std::size_t>(best)].result))
      best = i;
  }
  double best_log = 0.0;
  ClosedLoopResult best_run;
  if (best >= 0) {
    best_log = grid[static_cast<std::size_t>(best)].log_scale;
    best_run = grid[static_cast<std::size_t>(best)].result;
    for (int nb : {best - 1, best + 1}) {
      if (nb < 0 || nb >= static_cast<int>(grid.size())) continue;
      const Sample& other = grid[static_cast<std::size_t>(nb)];
      if (!other.result.stable) continue;
      const bool brackets =
          (best_run.free_rms_user_torque_nm - target) * (other.result.free_rms_user_torque_nm - target) <= 0.0;
      if (!brackets) continue;
      // RMS decreases with the scale: bisection on the sign of (RMS - target).
      double lo = std::min(best_log, other.log_scale), hi = std::max(best_log, other.log_scale);
      for (int i = 0; i < options.bisection_steps; ++i) {
        const double mid = 0.5 * (lo + hi);
        const ClosedLoopResult r = simulateJoint(withPidScale(scenario, std::exp(mid)));
        ++out.simulations;
        if (r.stable && mismatch(r) < mismatch(best_run)) {
          best_run = r;
          best_log = mid;
        }
        if (!r.stable || r.free_rms_user_torque_nm < target) {
          hi = mid;
        } else {
          lo = mid;
        }
      }
      break;
    }
  }
  out.pid_gain_scale = best >= 0 ? std::exp(best_log) : 0.0;
  out.pid_kp_v_per_nm = scenario.gains.torque_pid.kp_v_per_nm * out.pid_gain_scale;
  out.matched = best >= 0 && mismatch(best_run) <= std::log1p(options.transparency_tolerance);
  if (best >= 0) out.torque_pid = figures(best_run);

  // Largest stable wall for both at the compared gains.
  int sims = 0;
  out.admittance.max_stable_wall_nm_per_rad =
      largestStableWall(adm, options.wall_min_nm_per_rad, options.wall_max_nm_per_rad, options.bisection_steps, &sims);
  if (best >= 0) {
    out.torque_pid.max_stable_wall_nm_per_rad =
        largestStableWall(withPidScale(scenario, out.pid_gain_scale), options.wall_min_nm_per_rad,
                          options.wall_max_nm_per_rad, options.bisection_steps, &sims);
  }
  out.simulations += sims;
  return out;
}

}  // namespace fullarm::design
