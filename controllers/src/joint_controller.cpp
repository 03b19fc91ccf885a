#include "fullarm/controllers/joint_controller.hpp"

#include <Eigen/Core>
#include <cmath>
#include <numbers>
#include <unsupported/Eigen/MatrixFunctions>

#include "fullarm/core/config_error.hpp"

namespace fullarm::controllers {
namespace {

// Pole of the exact ZOH discretisation of 1/(s/(2 pi f) + 1); 0 (no filter) for f = 0.
double lowPassPole(double cutoff_hz, double dt_s) {
  return cutoff_hz > 0.0 ? std::exp(-2.0 * std::numbers::pi * cutoff_hz * dt_s) : 0.0;
}

double clamp(double x, double limit) noexcept {
  return x > limit ? limit : (x < -limit ? -limit : x);
}

bool finite(double x) noexcept {
  return std::isfinite(x);
}

}  // namespace

// Eq. (4): the model torque from the measured, contact and gravity torques (reports/equations.md).
PaperTorques paperTorques(const JointInput& in) noexcept {
  // Sign conventions: joint_controller.hpp file comment.
  return PaperTorques{-in.tau_load_cell_nm, -in.tau_contact_nm, -in.tau_gravity_nm};
}

// L1: exact ZOH of the impedance model; L2: first-order low-passes, exact ZOH pole (reports/equations.md).
JointControllerModel makeJointControllerModel(const JointGains& gains, ControllerKind kind, double dt_s) {
  validateJointGains(gains, dt_s, {}, gains.name);
  JointControllerModel m;
  m.gains = gains;
  m.kind = kind;
  m.dt_s = dt_s;
  // Eq. (3) of the DTS paper, x = [theta_m, omega_m], input u = tau + K_m theta_d:
  // x' = A x + b u, A = [0 1; -K/J -B/J], b = [0; 1/J]. Exact ZOH over one period from the
  // exponential of the augmented matrix [A b; 0 0] T (Van Loan).
  const ImpedanceParams& p = gains.impedance;
  Eigen::Matrix3d aug = Eigen::Matrix3d::Zero();
  aug(0, 1) = 1.0;
  aug(1, 0) = -p.stiffness_nm_per_rad / p.inertia_kgm2;
  aug(1, 1) = -p.damping_nms_per_rad / p.inertia_kgm2;
  aug(1, 2) = 1.0 / p.inertia_kgm2;
  const Eigen::Matrix3d e = (aug * dt_s).exp();
  for (int r = 0; r < 2; ++r) {
    for (int c = 0; c < 2; ++c) m.phi[r][c] = e(r, c);
    m.gamma[r] = e(r, 2);
  }
  m.torque_filter_pole = lowPassPole(gains.torque_filter_hz, dt_s);
  m.error_rate_filter_pole = lowPassPole(gains.error_rate_filter_hz, dt_s);
  return m;
}

void resetJointController(const JointControllerModel& /*model*/, JointControllerData& data, double q_rad) noexcept {
  data = JointControllerData{};
  data.theta_m_rad = q_rad;
  data.q_prev_rad = q_rad;
  data.status.clear();
  if (!finite(q_rad))
    data.status.raise(core::RtCode::kBadInput, kFaultNonFiniteInput, "non-finite joint angle at reset");
}

// L2: first-order low-passes, exact ZOH pole; L3: passivity observer and controller (reports/equations.md).
double stepJointController(const JointControllerModel& model, JointControllerData& data,
                           const JointInput& in) noexcept {
  // Safe output first: a latched fault keeps the valve at null.
  if (data.status.ok() &&
      !(finite(in.q_rad) && finite(in.tau_load_cell_nm) && finite(in.tau_contact_nm) && finite(in.tau_gravity_nm))) {
    data.status.raise(core::RtCode::kBadInput, kFaultNonFiniteInput, "non-finite controller input");
  }
  if (!data.status.ok()) {
    data.command_unsaturated_v = 0.0;
    data.valve_command_v = 0.0;
    data.saturated = false;
    data.po_damping_nms_per_rad = 0.0;
    return 0.0;
  }

  const JointGains& g = model.gains;
  const double T = model.dt_s;
  const PaperTorques paper = paperTorques(in);
  const bool first = !data.initialised;

  // Step 1: torque filter on the measured torque (starts at the first sample: no transient).
  const double a = first ? 0.0 : model.torque_filter_pole;
  data.tau_filtered_nm = a * data.tau_filtered_nm + (1.0 - a) * paper.tau_measured_nm;

  // Step 2: Eq. (4) of the DTS paper.
  double tau = assembleModelTorque(data.tau_filtered_nm, paper.tau_c_nm, paper.tau_gravity_expected_nm);

  // Passivity observer / controller (Hannaford & Ryu 2002) on the user's port.
  const double qdot = first ? 0.0 : (in.q_rad - data.q_prev_rad) / T;
  data.velocity_radps = qdot;
  data.po_power_w = (data.tau_filtered_nm - paper.tau_gravity_expected_nm) * qdot;
  double energy = data.po_energy_j + T * data.po_power_w;
  double alpha = 0.0;
  if (g.passivity.enabled && energy < 0.0 && std::abs(qdot) > g.passivity.velocity_threshold_radps && qdot != 0.0) {
    alpha = -energy / (T * qdot * qdot);
    if (alpha > g.passivity.max_damping_nms_per_rad) alpha = g.passivity.max_damping_nms_per_rad;
    tau -= alpha * qdot;
    const double dissipated = T * alpha * qdot * qdot;
    energy += dissipated;
    data.po_dissipated_j += dissipated;
  }
  data.po_energy_j = energy;
  data.po_damping_nms_per_rad = alpha;
  data.tau_model_nm = tau;

  // Step 3: the control law.
  double u = 0.0;
  bool saturated = false;
  if (model.kind == ControllerKind::kAdmittance) {
    // Eq. (3) with theta_d = q (the paper's choice), exact ZOH over one period.
    const double input = tau + g.impedance.stiffness_nm_per_rad * in.q_rad;
    const double theta =
        model.phi[0][0] * data.theta_m_rad + model.phi[0][1] * data.omega_m_radps + model.gamma[0] * input;
    const double omega =
        model.phi[1][0] * data.theta_m_rad + model.phi[1][1] * data.omega_m_radps + model.gamma[1] * input;
    data.theta_m_rad = theta;
    data.omega_m_radps = omega;
    // Eq. (5): theta_error = theta_m - theta_d.
    const double e = theta - in.q_rad;
    const double rate_raw = first ? 0.0 : (e - data.error_prev_rad) / T;
    const double b = first ? 0.0 : model.error_rate_filter_pole;
    data.error_rate_radps = b * data.error_rate_radps + (1.0 - b) * rate_raw;
    data.error_prev_rad = e;
    data.error_rad = e;
    // Eq. (6): sliding surface; Eq. (7): u = B_o sat(s / eps) (sign: file comment).
    const double s = data.error_rate_radps + g.sliding_mode.lambda_per_s * e;
    data.surface_radps = s;
    const double ratio = s / g.sliding_mode.boundary_layer_radps;
    saturated = std::abs(ratio) > 1.0;
    u = g.sliding_mode.valve_bound_v * saturate(ratio);
  } else {
    // The simple torque controller of §3.3: PID on the Eq. (4) torque.
    const TorquePidParams& pid = g.torque_pid;
    data.pid_integral_v = clamp(data.pid_integral_v + pid.ki_v_per_nms * T * tau, pid.integral_limit_v);
    const double rate = first ? 0.0 : (tau - data.tau_prev_nm) / T;
    u = pid.kp_v_per_nm * tau + data.pid_integral_v + pid.kd_vs_per_nm * rate;
  }
  data.tau_prev_nm = tau;
  data.q_prev_rad = in.q_rad;
  data.initialised = true;

  if (!(finite(u) && finite(data.theta_m_rad) && finite(data.omega_m_radps) && finite(data.error_rate_radps) &&
        finite(data.pid_integral_v) && finite(data.tau_filtered_nm) && finite(data.po_energy_j))) {
    data.status.raise(core::RtCode::kBadState, kFaultNonFiniteState, "non-finite controller state");
    data.command_unsaturated_v = 0.0;
    data.valve_command_v = 0.0;
    data.saturated = false;
    return 0.0;
  }

  // Step 4: output saturation.
  data.command_unsaturated_v = u;
  const double v = clamp(u, g.valve_limit_v);
  data.saturated = saturated || std::abs(u) > g.valve_limit_v;
  data.valve_command_v = v;
  return v;
}

}  // namespace fullarm::controllers
