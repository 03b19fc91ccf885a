#pragma once
/// @file
/// ArmPlant: the DTS master arm as a stiff ODE (rigid-body dynamics of fullarm::arm coupled to
/// one servovalve-actuated hydraulic joint per active DOF), integrated with CVODES (BDF, dense
/// direct linear solver, analytic Jacobian) one control period at a time.
///
/// State vector y (size 6 n for n active joints), in SI units:
///   y[4k+0] spool position x_v of joint k, normalised (1 = full opening)
///   y[4k+1] spool velocity [1/s]
///   y[4k+2] chamber A pressure p_a [Pa, gauge]
///   y[4k+3] chamber B pressure p_b [Pa, gauge]
///   y[4n+k] joint angle q [rad]
///   y[5n+k] joint velocity qd [rad/s]
/// Joints not active (the rest of the arm in single-joint mode, the hand joints) are locked at
/// their posture. Equations: docs/plant.md.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/joint_selection.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/arm/rigid_body_dynamics.hpp"
#include "fullarm/arm/rigid_body_reduction.hpp"
#include "fullarm/plant/hydraulics.hpp"
#include "fullarm/plant/joint_params.hpp"
#include "fullarm/plant/rosenbrock.hpp"
#include "fullarm/plant/sensor_model.hpp"

namespace fullarm::plant {

/// Largest number of active joints.
inline constexpr int kMaxPlantJoints = arm::kMaxJoints;
/// Largest state size.
inline constexpr int kMaxPlantStates = 6 * kMaxPlantJoints;

/// Fixed-capacity per-joint vector (no heap).
using JointVector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPlantJoints, 1>;

/// How CVODES gets the Newton matrix.
enum class JacobianKind {
  kAnalytic,          ///< analytic hydraulic and actuator terms; rigid-body q/qd gradients omitted
  kFiniteDifference,  ///< CVODE's internal dense difference quotients (slow; for checking)
};

/// Which integrator step() uses.
enum class IntegratorKind {
  kCvodes,  ///< CVODES BDF with root-found hard-stop events: the reference (default)
  kRodas3,  ///< adaptive one-step Rosenbrock (Rodas3) for real-time use; validated against CVODES
  kRodas4,  ///< the same with the order-4(3) scheme (Hairer & Wanner's RODAS)
  /// Rosenbrock-W ROS34PW2 (Rang & Angermann 2005): order 3(2) with the Jacobian built once per
  /// control period (and after two rejections in a row), the factorisation reused while h stays
  kRos34pw2,
};

/// Integrator settings.
struct SolverOptions {
  double rtol = 1e-6;
  double atol_spool = 1e-6;
  double atol_spool_rate_per_s = 1e-2;
  double atol_pressure_pa = 100.0;
  double atol_angle_rad = 1e-7;
  double atol_velocity_radps = 1e-5;
  long max_steps_per_period = 20000;
  /// Re-initialise CVODES when a command changes by more than this fraction of its full scale
  /// (valve mode: 1/amplifier gain volts; torque mode: the joint torque limit) in one period.
  double reinit_command_jump = 0.002;
  JacobianKind jacobian = JacobianKind::kAnalytic;
  /// kRodas3, kRodas4 and kRos34pw2 use rtol, the absolute tolerances, max_steps_per_period and the analytic
  /// Jacobian; they ignore reinit_command_jump and `jacobian` (docs/plant.md, Integration).
  IntegratorKind integrator = IntegratorKind::kCvodes;
  /// Rosenbrock integrators on a partial or whole arm, opt-in speed/accuracy trade: true computes
  /// the rigid-body derivatives d ID/d(q, qd) of the Jacobian (R6-R9) at the first Jacobian of
  /// each control period only and reuses them, with the current M^-1, in the period's later
  /// steps. Not exact after the first step, and the error estimate does not see the difference:
  /// on the arm chirp about 10 % faster (15 % before the composite derivatives, R13), the big joints' angle error
  /// against the tight reference about 2x larger (docs/plant.md). false (default): exact at every Jacobian.
  bool rigid_derivatives_once_per_period = false;
};

/// The accuracy reference the plant tests and `bench/plant_tolerance_sweep` compare an
/// integrator against: CVODES at rtol 1e-8 with every absolute tolerance of `base` 1000x tighter
/// (and room for the extra steps per period).
[[nodiscard]] inline SolverOptions tightReferenceOptions(SolverOptions base) noexcept {
  base.integrator = IntegratorKind::kCvodes;
  base.rtol = 1e-8;
  base.atol_spool *= 1e-3;
  base.atol_spool_rate_per_s *= 1e-3;
  base.atol_pressure_pa *= 1e-3;
  base.atol_angle_rad *= 1e-3;
  base.atol_velocity_radps *= 1e-3;
  base.max_steps_per_period = 200000;
  return base;
}

/// User arm strapped to the cuff: a point mass, a spring to the cuff's rest position and a
/// damper (Cartesian, world frame), on link `link` at `point_L` (link frame).
struct UserArmParams {
  bool enabled = false;
  int link = -1;
  Eigen::Vector3d point_L = Eigen::Vector3d::Zero();
  double mass_kg = 0.0;
  double stiffness_n_per_m = 0.0;
  double damping_ns_per_m = 0.0;
};

/// An explicit rigid load on one joint (single-joint mode without an arm model):
/// inertia J and gravity torque g(q) = gravity_cos_nm cos(q) + gravity_sin_nm sin(q), with
/// the sign of fullarm::arm's g(q) (the torque that holds the load still).
struct RigidLoad {
  double inertia_kgm2 = 0.05;
  double gravity_cos_nm = 0.0;
  double gravity_sin_nm = 0.0;
};

/// Inputs of one control period (held constant over it): subset vectors, indexed by active
/// joint in ArmPlant::selection() order (arm/joint_selection.hpp). All torques about the joint
/// axis, positive toward +q.
struct PlantCommand {
  JointVector command;      ///< valve voltage [V], desired torque [N m] or ideal torque [N m]
  JointVector tau_user_nm;  ///< torque the user applies at each joint [N m]
  /// Contact torque [N m]: the torque the environment applies to the link, positive toward +q
  /// (the same quantity and sign as fullarm::haptics' ContactData::tau_contact_nm, gathered at
  /// the active joints).
  JointVector tau_contact_nm;
  /// All zero for `n` joints.
  static PlantCommand zero(int n);
};

/// The continuous state of one joint.
struct JointState {
  double spool = 0.0;
  double spool_rate_per_s = 0.0;
  double p_a_pa = 0.0;
  double p_b_pa = 0.0;
  double q_rad = 0.0;
  double qd_radps = 0.0;
};

/// Solver counters, accumulated over CVodeReInit (which resets CVODES' own counters).
struct SolverStats {
  long steps = 0;
  long rhs_evals = 0;
  long jac_evals = 0;
  long nonlin_iters = 0;
  long nonlin_conv_fails = 0;
  long err_test_fails = 0;
  long root_events = 0;  ///< hard-stop contacts and releases
  long reinits = 0;
};

/// The plant. Configure once (allocates), reset, then step() at the control rate (no
/// allocation). Not copyable or movable (CVODES holds a pointer to it).
class ArmPlant {
 public:
  ArmPlant();
  ~ArmPlant();
  ArmPlant(const ArmPlant&) = delete;
  ArmPlant& operator=(const ArmPlant&) = delete;

  /// Whole arm: `joints` lists one JointParams per active joint (by name, in model order).
  /// @param posture initial posture of every model joint (locked joints stay there) [rad]
  /// @throws core::ConfigError for an unknown joint name or invalid parameters.
  void configure(const arm::ArmModel& model, const std::vector<JointParams>& joints, const Eigen::VectorXd& posture,
                 const UserArmParams& user, const SolverOptions& options, std::uint64_t seed = 1);
  /// One joint with an explicit rigid load (no arm model).
  void configure(const JointParams& joint, const RigidLoad& load, const SolverOptions& options, std::uint64_t seed = 1);

  /// Resets time to 0, the sensors, the statistics and the state: spool closed, pressures at
  /// the null-valve equilibrium (p_s + p_r)/2, q at the posture, at rest.
  void reset();
  /// Resets with an explicit state per active joint.
  void reset(const std::vector<JointState>& initial);

  /// Advances exactly one control period of `dt_s` with the command held (stop time at the
  /// boundary), re-initialising CVODES only at hard-stop events or large command jumps, then
  /// samples the sensors. Returns ok; kNotConfigured before configure(); kSolverFailure (CVODES:
  /// kFaultSolver; Rosenbrock: kFaultTooManySteps or kFaultStepTooSmall) or kBadState
  /// (kFaultNonFiniteState) when the integrator gave up, with the solver's own text in
  /// lastError().
  /// Allocation-free, unbounded time (core/rt_status.hpp): the adaptive integrators take as many
  /// steps as the solution needs, up to SolverOptions::max_steps_per_period.
  core::RtStatus step(double dt_s, const PlantCommand& command) noexcept;

  [[nodiscard]] int numJoints() const noexcept { return n_; }
  [[nodiscard]] int numStates() const noexcept { return 6 * n_; }
  [[nodiscard]] double time() const noexcept { return t_; }
  [[nodiscard]] const JointParams& joint(int k) const noexcept { return params_[static_cast<std::size_t>(k)]; }
  /// The active joints in the arm model: subset position k (the index of every per-joint
  /// input, state and output of the plant) <-> model joint (arm/joint_selection.hpp). Empty with
  /// an explicit load (no arm model).
  [[nodiscard]] const arm::JointSelection& selection() const noexcept { return selection_; }
  /// Index in the arm model of active joint k (-1 with an explicit load).
  [[nodiscard]] int modelIndex(int k) const noexcept { return selection_.size() > 0 ? selection_.modelIndex(k) : -1; }
  [[nodiscard]] JointState state(int k) const noexcept;
  /// Sensor readings of the last step.
  [[nodiscard]] const JointMeasurement& measurement(int k) const noexcept {
    return measured_[static_cast<std::size_t>(k)];
  }
  /// True torque through the load cell at the end of the last step [N m].
  [[nodiscard]] double transmittedTorque(int k) const noexcept { return tau_cell_[k]; }
  /// Torque the actuator fluid applies at the end of the last step [N m].
  [[nodiscard]] double hydraulicTorque(int k) const noexcept { return tau_hyd_[k]; }
  /// Joint accelerations at the end of the last step [rad/s^2].
  [[nodiscard]] const JointVector& accelerations() const noexcept { return qdd_; }
  [[nodiscard]] const SolverStats& stats() const noexcept { return stats_; }
  /// The solver's own text of the last failure, for a log (CVODES' message, or the Rosenbrock
  /// method, the time and the reason); empty if none. step()'s status carries the cause.
  [[nodiscard]] const char* lastError() const noexcept { return error_; }

  // Verification interface (tests): the right-hand side and the analytic Jacobian at (t, y)
  // for the command of the current period.
  /// Current state vector (size numStates()).
  [[nodiscard]] Eigen::VectorXd stateVector() const;
  /// dy/dt at y; also updates accelerations(), transmittedTorque() and hydraulicTorque(). @rt
  void evaluateRhs(const double* y, double* ydot) noexcept;
  /// The analytic Newton Jacobian df/dy at y into J (numStates() square, column-major). @rt
  void evaluateJacobian(const double* y, double* J) noexcept;
  /// Sets the command used by evaluateRhs/evaluateJacobian (step() sets it too). @rt
  void setCommand(const PlantCommand& command) noexcept { cmd_ = command; }

 private:
  struct Solver;  // CVODES handles (RAII), defined in the .cpp
  void allocate(const SolverOptions& options, std::uint64_t seed);
  void mechanics(const double* y) noexcept;
  // evaluateRhs() in two passes: M, h, actuator torques, qdd and tau_cell at y (all the sensors
  // and outputs need), then the state derivatives.
  void evaluateTorques(const double* y) noexcept;
  void evaluateRates(const double* y, double* ydot) noexcept;
  void jacobianEntries(const double* y, double* J) noexcept;
  void rigidBodyGradients(const double* y, double* J, int ld) noexcept;
  /// J(qd rows, q and qd columns) -= M^-1 [d ID/dq, d ID/dqd]; N > 0: n at compile time.
  template <int N>
  void subtractMinvTimesDerivatives(double* J, int ld) const noexcept;
  void reinitSolver() noexcept;
  void harvestStats() noexcept;
  void initialiseSensors() noexcept;
  void singleAxisCuff(double q, double qd, double& tau, double& dtau_dq, double& dtau_dqd) const noexcept;

  friend struct SolverCallbacks;

  int n_ = 0;
  std::vector<JointParams> params_;
  arm::JointSelection selection_;
  double t_ = 0.0;
  SolverOptions options_{};
  PlantCommand cmd_{};
  PlantCommand last_cmd_{};
  bool need_reinit_ = true;
  bool cvodes_counters_stale_ = true;  // CVODES' counters are the previous run's (after reset())
  SolverStats stats_{};
  SolverStats stats_base_{};
  char error_[256] = {};

  // Mechanics.
  bool single_axis_ = true;
  RigidLoad load_{};
  std::unique_ptr<arm::ArmModel> model_;  // copy with the user mass merged into its link
  std::unique_ptr<arm::ArmData> data_;
  Eigen::VectorXd posture_;
  // The arm reduced to the active joints (locked links merged): the per-step rigid-body
  // dynamics and its analytic derivatives (arm/rigid_body_dynamics.hpp).
  std::unique_ptr<arm::RigidBodyModel> reduced_;
  std::unique_ptr<arm::RigidBodyData> reduced_data_;
  arm::BodyPoint cuff_point_{};
  JointVector q_, qd_, zero_;
  // (q, qd) of the last full mechanics() pass: its outputs are reused at the same state.
  JointVector mechanics_q_, mechanics_qd_;
  bool mechanics_valid_ = false;
  bool rigid_body_gradients_ = false;
  bool rigid_derivatives_stale_ = true;  // set by each step(): the next Jacobian recomputes them
  arm::BodyMatrix rigid_dq_, rigid_dqd_;
  JointVector rigid_tau_;
  UserArmParams user_{};
  Eigen::Vector3d cuff_anchor_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis_W_ = Eigen::Vector3d::UnitZ();  // single axis from an arm model
  Eigen::Vector3d origin_W_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d cuff0_W_ = Eigen::Vector3d::Zero();
  bool single_axis_cuff_ = false;
  Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, kMaxPlantJoints> cuff_jac_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPlantJoints, kMaxPlantJoints> mass_, mass_inv_;
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, kMaxPlantJoints, kMaxPlantJoints> chol_;  // M = L L^T
  JointVector qdd_, tau_cell_, tau_hyd_, tau_act_, h_, tau_cuff_;
  std::vector<StrokeRange> stroke_;
  std::vector<SinCos> lever_offset_;     // per joint: sin, cos of the cylinder's lever angle offset
  SinCos single_axis_sincos_{};          // sin q, cos q of the single-axis load at the last mechanics()
  std::vector<ChamberVolumes> volumes_;  // per joint, at the state of the last evaluateRhs()
  // Per-joint terms of the last evaluateRhs() that evaluateJacobian() reuses (value and slopes).
  struct JointTerms {
    ValveFlows flows;
    ValueSlope beta_a, beta_b, check_a, check_b, friction;
    StopTorque stop;
  };
  std::vector<JointTerms> terms_;
  std::vector<double> air_root_;  // p_atm^(1/n) per joint (H3)
  double ydot_scratch_[kMaxPlantStates] = {};

  // Sensors.
  GaussianNoise noise_{1};
  /// The pressure transducers' noise, a stream of its own (sensor_model.hpp).
  GaussianNoise pressure_noise_{2};
  static constexpr std::uint64_t kPressureNoiseStream = 0x70726573737572ULL;
  std::uint64_t seed_ = 1;
  std::vector<JointSensorState> sensor_state_;
  std::vector<JointMeasurement> measured_;

  std::unique_ptr<Solver> solver_;
  std::unique_ptr<RosenbrockIntegrator> rodas_;  // set when options_.integrator == kRodas3
  std::vector<signed char> stop_side_;           // -1 below min, 0 inside, 1 above max (Rodas3 event count)
  core::RtStatus stepRodas3(double dt_s) noexcept;
  void sampleOutputs(double dt_s) noexcept;
};

}  // namespace fullarm::plant
