#include "fullarm/design/closed_loop.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/plant/hydraulics.hpp"

namespace fullarm::design {
namespace {

// Keeps the start this far inside the joint limits [rad].
constexpr double kLimitMarginRad = 0.05;
// The motion (free move + gap + push) uses at most this fraction of the room to the far limit.
constexpr double kRoomFraction = 0.8;
// Onset window after the start of the free move [s].
constexpr double kOnsetWindowS = 0.1;
constexpr double kSustainRatio = kOscillationSustainRatio;
// The wall chatters when, over the last contact window, the standard deviation of the rendered
// wall torque exceeds this fraction of its mean magnitude (the wall switches on and off) and
// kChatterFloorNm (so that a barely touched wall does not count).
constexpr double kChatterRatio = 0.5;
constexpr double kChatterFloorNm = 0.5;

// Windowed statistics of a signal recorded once per period.
struct Window {
  double sum = 0.0, sum_sq = 0.0;
  long count = 0;
  void add(double x) {
    sum += x;
    sum_sq += x * x;
    ++count;
  }
  [[nodiscard]] double mean() const { return count > 0 ? sum / static_cast<double>(count) : 0.0; }
  [[nodiscard]] double rms() const { return count > 0 ? std::sqrt(sum_sq / static_cast<double>(count)) : 0.0; }
};

// Standard deviation of x[begin, end) about its mean.
double deviation(const std::vector<double>& x, std::size_t begin, std::size_t end) {
  end = std::min(end, x.size());
  if (begin >= end) return 0.0;
  double mean = 0.0;
  for (std::size_t i = begin; i < end; ++i) mean += x[i];
  mean /= static_cast<double>(end - begin);
  double sq = 0.0;
  for (std::size_t i = begin; i < end; ++i) sq += (x[i] - mean) * (x[i] - mean);
  return std::sqrt(sq / static_cast<double>(end - begin));
}

// Zero crossings of x - mean over [begin, end), as a frequency for period T.
double crossingFrequency(const std::vector<double>& x, std::size_t begin, std::size_t end, double T) {
  end = std::min(end, x.size());
  if (end < begin + 3) return 0.0;
  double mean = 0.0;
  for (std::size_t i = begin; i < end; ++i) mean += x[i];
  mean /= static_cast<double>(end - begin);
  int crossings = 0;
  for (std::size_t i = begin + 1; i < end; ++i) {
    if ((x[i - 1] - mean) * (x[i] - mean) < 0.0) ++crossings;
  }
  return crossings / (2.0 * static_cast<double>(end - begin) * T);
}

// The detector of closed_loop.hpp on the hold ending at sample `end`: returns the late
// window's deviation; `sustained` when it exceeds the threshold and has not decayed.
struct HoldVerdict {
  double late = 0.0;
  double early = 0.0;
  bool oscillating = false;
  std::size_t begin = 0, end = 0;
};
HoldVerdict examineHold(const std::vector<double>& qd, std::size_t end, std::size_t window, double threshold) {
  HoldVerdict v;
  v.end = end;
  v.begin = end >= window ? end - window : 0;
  const std::size_t early_begin = v.begin >= window ? v.begin - window : 0;
  v.late = deviation(qd, v.begin, end);
  v.early = deviation(qd, early_begin, v.begin);
  v.oscillating = qd.size() >= end && v.late > threshold && v.late > kSustainRatio * v.early;
  return v;
}

// Pressures that hold `torque_nm` at `q_rad` with a closed valve: p_a - p_b = tau / (A R).
plant::JointState holdingState(const plant::JointParams& p, double q_rad, double torque_nm) {
  plant::JointState s;
  s.q_rad = q_rad;
  const double mid = 0.5 * (p.supply_pressure_pa + p.return_pressure_pa);
  const double ratio = std::abs(plant::actuatorKinematics(p.actuator, q_rad).ratio);
  const double area = 0.5 * (plant::areaA(p.actuator) + plant::areaB(p.actuator));
  double dp = area * ratio > 0.0 ? torque_nm / (area * ratio) : 0.0;
  const double max_dp = 0.9 * (p.supply_pressure_pa - p.return_pressure_pa);
  dp = std::clamp(dp, -max_dp, max_dp);
  s.p_a_pa = mid + 0.5 * dp;
  s.p_b_pa = mid - 0.5 * dp;
  return s;
}

// The wall torque the true joint state would meet (what the arm physically does against the
// wall, free of the sensor noise that the rendered wall sees through its damping term).
double trueWallTorque(const JointScenario& sc, double q_wall, const plant::JointState& st) {
  const double d = sc.direction;
  const double pen = d * (st.q_rad - q_wall);
  if (!sc.wall.enabled || pen <= 0.0) return 0.0;
  const double push = sc.wall.stiffness_nm_per_rad * pen + sc.wall.damping_nms_per_rad * d * st.qd_radps;
  return -d * std::max(0.0, push);
}

}  // namespace

// V1: minimum-jerk reference (reports/equations.md).
MinJerk minimumJerk(double t_s, double duration_s) noexcept {
  if (!(duration_s > 0.0)) return {t_s >= 0.0 ? 1.0 : 0.0, 0.0};
  const double s = std::clamp(t_s / duration_s, 0.0, 1.0);
  const double s2 = s * s;
  const double pos = s2 * s * (10.0 - 15.0 * s + 6.0 * s2);
  const double rate = (t_s <= 0.0 || t_s >= duration_s) ? 0.0 : 30.0 * s2 * (1.0 - s) * (1.0 - s) / duration_s;
  return {pos, rate};
}

double wallPosition(const JointScenario& sc) noexcept {
  return sc.start_rad + sc.direction * (sc.timing.free_move_rad + sc.timing.wall_gap_rad);
}

MinJerk scenarioReference(const JointScenario& sc, double t_s) noexcept {
  const ScenarioTiming& tm = sc.timing;
  const double d = sc.direction;
  const double t_free = t_s - tm.rest_s;
  const MinJerk free = minimumJerk(t_free, tm.free_move_s);
  const double t_contact = t_free - tm.free_move_s - tm.free_hold_s;
  const MinJerk contact = minimumJerk(t_contact, tm.contact_move_s);
  const double contact_travel = tm.wall_gap_rad + tm.push_rad;
  return {sc.start_rad + d * (tm.free_move_rad * free.position + contact_travel * contact.position),
          d * (tm.free_move_rad * free.rate_per_s + contact_travel * contact.rate_per_s)};
}

JointScenario makeJointScenario(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                const controllers::GainsConfig& gains, std::string_view name) {
  JointScenario sc;
  const plant::JointParams& joint =
      plant_config.joints[static_cast<std::size_t>(plant::findPlantJoint(plant_config, name))];
  const controllers::JointGains& g =
      gains.joints[static_cast<std::size_t>(controllers::findGainsJoint(gains, joint.name))];
  const int index = model.jointIndex(joint.name);
  if (index < 0)
    throw core::ConfigError(plant_config.source, "joints", "joint " + joint.name + " not in the arm model");
  sc.joint_name = joint.name;
  sc.joint = joint;
  sc.solver = plant_config.solver;
  sc.noise_seed = plant_config.seed;
  sc.gains = g;
  sc.kind = gains.controller;
  sc.dt_s = gains.control_period_s;

  // Link inertia and gravity about this joint's axis with the rest of the arm at its posture.
  Eigen::VectorXd q = model.defaultPosture();
  const double lo = joint.min_rad + kLimitMarginRad;
  const double hi = joint.max_rad - kLimitMarginRad;
  sc.start_rad = std::clamp(q[index], lo, hi);
  q[index] = sc.start_rad;
  const arm::SingleAxisLoad axis = arm::computeSingleAxisLoad(model, index, q);
  sc.load.inertia_kgm2 = axis.inertia_kgm2 + sc.user.inertia_kgm2;
  sc.load.gravity_cos_nm = axis.gravity_cos_nm;
  sc.load.gravity_sin_nm = axis.gravity_sin_nm;
  sc.expected_gravity_cos_nm = sc.load.gravity_cos_nm;
  sc.expected_gravity_sin_nm = sc.load.gravity_sin_nm;

  // Move toward the farther limit; shrink the motion to fit.
  const double up = hi - sc.start_rad;
  const double down = sc.start_rad - lo;
  sc.direction = up >= down ? 1 : -1;
  const double room = std::max(up, down);
  ScenarioTiming& tm = sc.timing;
  const double travel = tm.free_move_rad + tm.wall_gap_rad + tm.push_rad;
  if (travel > kRoomFraction * room) {
    const double scale = kRoomFraction * room / travel;
    tm.free_move_rad *= scale;
    tm.wall_gap_rad *= scale;
    tm.push_rad *= scale;
  }
  return sc;
}

ClosedLoopResult simulateJoint(const JointScenario& sc, ClosedLoopTrace* trace) {
  ClosedLoopResult r;
  plant::ArmPlant plant;
  plant.configure(sc.joint, sc.load, sc.solver, sc.noise_seed);
  const double g0 = sc.load.gravity_cos_nm * std::cos(sc.start_rad) + sc.load.gravity_sin_nm * std::sin(sc.start_rad);
  plant.reset({holdingState(sc.joint, sc.start_rad, g0)});

  const controllers::JointControllerModel cm = controllers::makeJointControllerModel(sc.gains, sc.kind, sc.dt_s);
  controllers::JointControllerData cd;
  controllers::resetJointController(cm, cd, plant.measurement(0).q_rad);

  const ScenarioTiming& tm = sc.timing;
  const double T = sc.dt_s;
  const double t_free0 = tm.rest_s;
  const double t_free1 = t_free0 + tm.free_move_s;
  const double t_hold1 = t_free1 + tm.free_hold_s;
  const double t_contact1 = t_hold1 + tm.contact_move_s;
  const double t_end = t_contact1 + tm.contact_hold_s;
  const long steps = std::lround(t_end / T);
  const double q_wall = wallPosition(sc);
  const double d = sc.direction;

  const int delay = std::max(0, sc.delay_samples);
  std::vector<double> line(static_cast<std::size_t>(delay) + 1, 0.0);
  if (trace != nullptr) *trace = ClosedLoopTrace{};

  Window free_torque, contact_pen, contact_env, contact_user, contact_env_dev;
  std::vector<double> tau_env_log;  // rendered (measured angle) wall torque
  tau_env_log.reserve(static_cast<std::size_t>(steps));
  std::vector<double> tau_wall_true_log;  // the wall torque of the true joint state
  tau_wall_true_log.reserve(static_cast<std::size_t>(steps));
  std::vector<double> qd_true;
  qd_true.reserve(static_cast<std::size_t>(steps));
  const auto window = static_cast<std::size_t>(std::lround(tm.detect_window_s / T));
  const auto free_hold_end = static_cast<std::size_t>(std::lround(t_hold1 / T));
  const auto contact_hold_end = static_cast<std::size_t>(steps);
  double q_meas_prev = plant.measurement(0).q_rad;
  double min_energy = 0.0;
  plant::PlantCommand cmd = plant::PlantCommand::zero(1);
  for (long k = 0; k < steps; ++k) {
    const double t = static_cast<double>(k) * T;
    const plant::JointMeasurement& m = plant.measurement(0);
    const plant::JointState st = plant.state(0);
    const MinJerk ref = scenarioReference(sc, t);
    const double tau_user = sc.user.stiffness_nm_per_rad * (ref.position - st.q_rad) +
                            sc.user.damping_nms_per_rad * (ref.rate_per_s - st.qd_radps);

    // The virtual wall, from the measured angle (what the haptic loop knows).
    const double qd_meas = k == 0 ? 0.0 : (m.q_rad - q_meas_prev) / T;
    q_meas_prev = m.q_rad;
    double tau_env = 0.0;
    const double pen = d * (m.q_rad - q_wall);
    if (sc.wall.enabled && pen > 0.0) {
      const double push = sc.wall.stiffness_nm_per_rad * pen + sc.wall.damping_nms_per_rad * d * qd_meas;
      tau_env = -d * std::max(0.0, push);
    }

    controllers::JointInput in;
    in.q_rad = m.q_rad;
    in.tau_load_cell_nm = m.tau_nm;
    if (sc.inject_nan_torque_at_s >= 0.0 && t >= sc.inject_nan_torque_at_s) {
      in.tau_load_cell_nm = std::numeric_limits<double>::quiet_NaN();
    }
    in.tau_contact_nm = tau_env;
    in.tau_gravity_nm = sc.expected_gravity_cos_nm * std::cos(m.q_rad) + sc.expected_gravity_sin_nm * std::sin(m.q_rad);
    const double v = controllers::stepJointController(cm, cd, in);
    min_energy = std::min(min_energy, cd.po_energy_j);

    // Computation delay: the command computed now acts `delay` periods later.
    std::rotate(line.rbegin(), line.rbegin() + 1, line.rend());
    line[0] = v;
    cmd.command[0] = line[static_cast<std::size_t>(delay)];
    cmd.tau_user_nm[0] = tau_user;
    cmd.tau_contact_nm[0] = 0.0;

    if (trace != nullptr) {
      trace->t_s.push_back(t);
      trace->q_rad.push_back(st.q_rad);
      trace->q_ref_rad.push_back(ref.position);
      trace->qd_radps.push_back(st.qd_radps);
      trace->tau_user_nm.push_back(tau_user);
      trace->tau_env_nm.push_back(tau_env);
      trace->tau_cell_nm.push_back(m.tau_nm);
      trace->valve_v.push_back(v);
      trace->po_energy_j.push_back(cd.po_energy_j);
    }

    // Figures of merit.
    if (t >= t_free0 && t < t_free1) {
      free_torque.add(tau_user);
      r.free_peak_user_torque_nm = std::max(r.free_peak_user_torque_nm, std::abs(tau_user));
      if (t < t_free0 + kOnsetWindowS) r.onset_peak_valve_v = std::max(r.onset_peak_valve_v, std::abs(v));
    }
    qd_true.push_back(st.qd_radps);
    tau_env_log.push_back(tau_env);
    tau_wall_true_log.push_back(trueWallTorque(sc, q_wall, st));
    if (t >= t_end - tm.detect_window_s) {
      contact_pen.add(d * (st.q_rad - q_wall));
      contact_env.add(std::abs(tau_env));
      contact_env_dev.add(tau_env);
      contact_user.add(std::abs(tau_user));
    }

    if (!plant.step(T, cmd).ok()) {
      r.solver_ok = false;
      r.failure = std::string("plant solver failure: ") + plant.lastError();
      break;
    }
    const plant::JointState after = plant.state(0);
    if (!std::isfinite(after.q_rad) || after.q_rad >= sc.joint.max_rad || after.q_rad <= sc.joint.min_rad) {
      r.hit_stop = true;
      if (r.failure.empty()) r.failure = "joint reached a hard stop at t = " + std::to_string(t) + " s";
      break;
    }
  }

  r.controller_faults = cd.status.faults;
  r.free_rms_user_torque_nm = free_torque.rms();
  const HoldVerdict free_v = examineHold(qd_true, free_hold_end, window, sc.oscillation_speed_radps);
  const HoldVerdict contact_v = examineHold(qd_true, contact_hold_end, window, sc.oscillation_speed_radps);
  r.free_hold_speed_rms_radps = free_v.late;
  r.contact_hold_speed_rms_radps = contact_v.late;
  r.free_hold_early_speed_rms_radps = free_v.early;
  r.contact_hold_early_speed_rms_radps = contact_v.early;
  r.contact_penetration_rad = contact_pen.mean();
  r.contact_wall_torque_nm = contact_env.mean();
  r.contact_user_torque_nm = contact_user.mean();
  r.wall_reached = r.contact_wall_torque_nm > 0.0 && r.contact_wall_torque_nm >= 0.5 * r.contact_user_torque_nm;
  r.contact_rendered_stiffness_nm_per_rad = contact_pen.mean() > 0.0 ? contact_user.mean() / contact_pen.mean() : 0.0;
  r.min_po_energy_j = min_energy;
  r.po_dissipated_j = cd.po_dissipated_j;
  r.solver_steps = plant.stats().steps;
  const bool free_osc = free_v.oscillating;
  r.contact_rendered_wall_torque_deviation_nm =
      contact_env_dev.rms() > 0.0 ? deviation(tau_env_log, contact_v.begin, contact_v.end) : 0.0;
  // Chatter is judged on the wall torque of the true joint motion (see closed_loop.hpp).
  const double env_dev = deviation(tau_wall_true_log, contact_v.begin, contact_v.end);
  double true_mean = 0.0;
  for (std::size_t i = contact_v.begin; i < std::min(contact_v.end, tau_wall_true_log.size()); ++i) {
    true_mean += std::abs(tau_wall_true_log[i]);
  }
  if (contact_v.end > contact_v.begin) true_mean /= static_cast<double>(contact_v.end - contact_v.begin);
  r.contact_wall_torque_deviation_nm = env_dev;
  // The wall switches on and off: contact made, then lost, inside the window (a late first
  // contact, the wall torque rising from zero once, is not chatter).
  bool touched = false;
  for (std::size_t i = contact_v.begin; i < std::min(contact_v.end, tau_wall_true_log.size()); ++i) {
    if (tau_wall_true_log[i] != 0.0) {
      touched = true;
    } else if (touched) {
      r.contact_lost = true;
      break;
    }
  }
  const bool chatter = r.contact_lost && env_dev > kChatterFloorNm && env_dev > kChatterRatio * true_mean;
  const bool contact_osc = contact_v.oscillating || chatter;
  r.oscillating = free_osc || contact_osc;
  const HoldVerdict& worst = contact_v.late >= free_v.late ? contact_v : free_v;
  r.oscillation_frequency_hz = crossingFrequency(qd_true, worst.begin, worst.end, T);
  if (r.oscillating && r.failure.empty()) {
    if (chatter && !contact_v.oscillating && !free_osc) {
      r.failure = "wall chatter (wall torque deviation " + std::to_string(env_dev) + " N m about a mean of " +
                  std::to_string(true_mean) + " N m)";
    } else {
      r.failure = std::string(contact_osc ? "oscillation in contact" : "oscillation in free space") +
                  " (speed deviation " +
                  std::to_string(std::max(r.free_hold_speed_rms_radps, r.contact_hold_speed_rms_radps)) + " rad/s)";
    }
  }
  if (r.controller_faults != controllers::kFaultNone && r.failure.empty()) r.failure = "controller fault";
  r.stable = r.solver_ok && !r.hit_stop && !r.oscillating && r.controller_faults == controllers::kFaultNone;
  const double breakaway_nm = std::max(sc.joint.friction.static_nm, sc.joint.friction.coulomb_nm);
  r.sluggish_push_limit_nm = sc.sluggish_push_friction_ratio * breakaway_nm;
  r.sluggish = r.stable && sc.wall.enabled && !r.wall_reached && r.contact_user_torque_nm > r.sluggish_push_limit_nm;
  if (r.sluggish) {
    r.failure = "too sluggish: wall not reached under a mean push of " + std::to_string(r.contact_user_torque_nm) +
                " N m (breakaway " + std::to_string(breakaway_nm) + " N m)";
  }
  return r;
}

}  // namespace fullarm::design
