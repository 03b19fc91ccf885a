#pragma once
/// @file
/// The DTS joint torque controllers of §3.3 of the DTS paper, one joint at a time: the
/// admittance controller (impedance model Eq. 3, torque assembly Eq. 4, sliding-mode position
/// loop Eq. 6-7) and the "simple torque controller" baseline (PID on the Eq. 4 torque), with a
/// torque filter, a Hannaford-Ryu passivity observer/controller, output saturation and fault
/// handling. Model/Data split: JointControllerModel is constant after makeJointControllerModel();
/// JointControllerData holds the state; stepJointController() is @rt.
///
/// ## Sign conventions (all torques about the joint axis, positive in the +q direction)
///
/// The inputs use the conventions of fullarm::plant, fullarm::arm and fullarm::haptics:
///  - `tau_load_cell_nm`: the load-cell reading, the torque the actuator transmits to the link
///    (positive drives the link toward +q). A joint at rest reads g(q) - tau_user - tau_env.
///  - `tau_contact_nm`: the contact torque, the torque the (virtual) environment applies to the
///    link, positive toward +q (a wall on the +q side pushes with a negative torque). The same
///    quantity, under the same name and sign, as fullarm::haptics' ContactData::tau_contact_nm
///    and fullarm::plant's PlantCommand::tau_contact_nm.
///  - `tau_gravity_nm`: fullarm::arm's g(q) = dV/dq, the torque that holds the link still.
/// The paper's quantities of Eq. (4), tau = (tau_u + tau_ga) - (tau_c + tau_ge), are then
///  - tau_u + tau_ga = -tau_load_cell_nm  (what the user and gravity push on the actuator),
///  - tau_c          = -tau_contact_nm    (what the virtual arm pushes on the environment; named
///    tau_c_nm, and used only where Eq. (4) is assembled),
///  - tau_ge         = -tau_gravity_nm    (the expected gravity load, in the same sense),
/// so tau = tau_gravity_nm + tau_contact_nm - tau_load_cell_nm, which for a link at rest equals
/// tau_user + tau_contact (gravity cancels when the model is exact).
///  - Output: the valve command [V], positive opens the valve to move the joint toward +q (the
///    sense of fullarm::plant's valve_voltage input).
///
/// ## Discrete-time law, executed once per control period T (in this order)
///  1. tau_f[k] = a tau_f[k-1] + (1 - a) tau_meas[k], a = exp(-2 pi f_tau T) (exact ZOH of
///     1/(s/(2 pi f_tau) + 1); a = 0 without filter), tau_meas = tau_u + tau_ga = -load cell.
///  2. Eq. (4): tau[k] = tau_f[k] - tau_c[k] - tau_ge[k].
///     Passivity observer (Hannaford & Ryu 2002) on the user's port, effort the estimated user
///     torque tau_f - tau_ge, flow qdot[k] = (q[k] - q[k-1]) / T:
///     E'[k] = E[k-1] + T (tau_f[k] - tau_ge[k]) qdot[k]. Passivity controller (when enabled):
///     if E'[k] < 0 and |qdot| > threshold, alpha = min(-E'[k] / (T qdot^2), alpha_max), else 0;
///     tau[k] -= alpha qdot[k] and E[k] = E'[k] + T alpha qdot^2 (the energy it dissipates).
///     The damping acts on the model input (admittance-type passivity control): in the linear
///     region the arm follows the model, so it acts as a damper at the user's port.
///  3. Admittance: Eq. (3) with theta_d = q[k], integrated exactly over one period with the input
///     tau[k] + K_m q[k] held (zero-order hold): [theta_m, omega_m][k+1] = Phi [.,.][k] + Gamma (..).
///     e[k] = theta_m[k+1] - q[k] (Eq. 5: the model ahead of the arm is a positive error);
///     e'[k] = (e[k] - e[k-1]) / T, optionally low-passed with b = exp(-2 pi f_e T);
///     s[k] = e'[k] + lambda e[k] (Eq. 6); u[k] = B_o sat(s[k] / eps) (Eq. 7, written for the
///     error of Eq. 5, whose sign is opposite to the plant-minus-reference error Eq. 7 assumes,
///     so that a model ahead of the arm opens the valve toward it).
///     Torque PID: u[k] = kp tau[k] + clamp(ki T sum tau, +-I) + kd (tau[k] - tau[k-1]) / T.
///  4. v[k] = clamp(u[k], +-valve_limit_v).
/// In the linear region step 3 is Eq. (8): u = (B_o/eps)(s + lambda) theta_error.
///
/// ## Faults
/// The controller's status is a core::RtStatus (JointControllerData::status). A non-finite input
/// (angle, load cell, environment or gravity torque) raises kFaultNonFiniteInput, a non-finite
/// internal state kFaultNonFiniteState, a step before resetJointController() is
/// kFaultNotConfigured; any of them makes the command exactly 0 V (the valve at null: the joint
/// holds still) and latches until resetJointController().

#include "fullarm/controllers/gains.hpp"
#include "fullarm/core/rt_status.hpp"

namespace fullarm::controllers {

// The fault bits the controllers raise (core/rt_status.hpp), by their names in this namespace.
using core::kFaultNone;
using core::kFaultNonFiniteInput;
using core::kFaultNonFiniteState;
using core::kFaultNotConfigured;

/// Inputs of one control period for one joint (conventions in the file comment).
struct JointInput {
  double q_rad = 0.0;             ///< measured joint angle
  double tau_load_cell_nm = 0.0;  ///< measured load-cell torque
  double tau_contact_nm = 0.0;    ///< contact torque: the environment's torque on the link
  double tau_gravity_nm = 0.0;    ///< expected gravity holding torque g(q)
};

/// The paper's torques of Eq. (4) from the plant/arm/haptics conventions (file comment).
struct PaperTorques {
  double tau_measured_nm = 0.0;          ///< tau_u + tau_ga
  double tau_c_nm = 0.0;                 ///< tau_c = -tau_contact_nm: what the arm pushes on the environment
  double tau_gravity_expected_nm = 0.0;  ///< tau_ge
};

/// Maps the inputs to the paper's quantities. @rt
[[nodiscard]] PaperTorques paperTorques(const JointInput& in) noexcept;

/// Eq. (4) of the DTS paper: tau = (tau_u + tau_ga) - (tau_c + tau_ge). @rt
[[nodiscard]] constexpr double assembleModelTorque(double tau_measured_nm, double tau_c_nm,
                                                   double tau_gravity_expected_nm) noexcept {
  return tau_measured_nm - (tau_c_nm + tau_gravity_expected_nm);
}

/// sat(x) = clamp(x, -1, 1), the saturation that replaces sign() in Eq. (7). @rt
[[nodiscard]] constexpr double saturate(double x) noexcept {
  return x > 1.0 ? 1.0 : (x < -1.0 ? -1.0 : x);
}

/// Constant, precomputed description of one joint's controller.
struct JointControllerModel {
  JointGains gains{};
  ControllerKind kind = ControllerKind::kAdmittance;
  double dt_s = 1.0e-3;
  /// Exact ZOH discretisation of Eq. (3) (x = [theta_m, omega_m], input tau + K_m theta_d):
  /// x[k+1] = phi x[k] + gamma u. Row-major 2x2 and 2x1.
  double phi[2][2] = {{1.0, 0.0}, {0.0, 1.0}};
  double gamma[2] = {0.0, 0.0};
  double torque_filter_pole = 0.0;      ///< a of step 1 (0 = no filter)
  double error_rate_filter_pole = 0.0;  ///< b of step 3 (0 = no filter)
};

/// Builds the model (validates `gains`, discretises Eq. 3 with the matrix exponential).
/// @param dt_s control period [s] (> 0)
/// @throws core::ConfigError for invalid gains or period.
[[nodiscard]] JointControllerModel makeJointControllerModel(const JointGains& gains, ControllerKind kind, double dt_s);

/// State and last outputs of one joint's controller (no heap).
struct JointControllerData {
  // State.
  double theta_m_rad = 0.0;       ///< impedance model angle
  double omega_m_radps = 0.0;     ///< impedance model velocity
  double tau_filtered_nm = 0.0;   ///< filtered tau_u + tau_ga
  double error_prev_rad = 0.0;    ///< e[k-1]
  double error_rate_radps = 0.0;  ///< filtered e'[k]
  double q_prev_rad = 0.0;        ///< q[k-1]
  double pid_integral_v = 0.0;    ///< ki T sum tau (clamped)
  double tau_prev_nm = 0.0;       ///< tau[k-1] for the PID derivative
  bool initialised = false;
  /// ok, or the first fault and every fault bit since the last reset (latched).
  core::RtStatus status =
      core::RtStatus::fault(core::RtCode::kNotConfigured, kFaultNotConfigured, "controller not reset");

  // Outputs of the last step (telemetry).
  double tau_model_nm = 0.0;           ///< Eq. (4) torque fed to the model / the PID
  double error_rad = 0.0;              ///< theta_error of Eq. (5)
  double surface_radps = 0.0;          ///< s of Eq. (6)
  double velocity_radps = 0.0;         ///< backward-difference joint velocity
  double command_unsaturated_v = 0.0;  ///< u before the valve limit
  double valve_command_v = 0.0;        ///< the output
  bool saturated = false;              ///< |s/eps| > 1 or the valve limit was hit
  // Passivity observer (Hannaford & Ryu 2002), energy into the device from the user's port.
  double po_energy_j = 0.0;             ///< E_obs[k] = T sum (tau_user_est qdot) + dissipated
  double po_dissipated_j = 0.0;         ///< energy the passivity controller has dissipated
  double po_power_w = 0.0;              ///< tau_user_est[k] qdot[k]
  double po_damping_nms_per_rad = 0.0;  ///< alpha of the last step (0 when not acting)
};

/// Sets the state for a joint at rest at `q_rad` (model at the arm, filters at zero, energy 0,
/// faults cleared). @rt
void resetJointController(const JointControllerModel& model, JointControllerData& data, double q_rad) noexcept;

/// One control period (order and equations in the file comment). Returns the valve command
/// [V], |v| <= valve_limit_v; exactly 0 while a fault is latched. @rt
double stepJointController(const JointControllerModel& model, JointControllerData& data,
                           const JointInput& input) noexcept;

}  // namespace fullarm::controllers
