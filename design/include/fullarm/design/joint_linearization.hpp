#pragma once
/// @file
/// Linearisation of one DTS joint as the plant simulates it in single-joint mode (the rest of
/// the arm locked): the servovalve spool, the two chamber pressures, the link with its gravity
/// load and the user's arm at the cuff (docs/analysis.md; plant equations H1-H15 of
/// reports/equations.md). The Jacobian is analytic, from the free functions of
/// fullarm/plant/hydraulics.hpp; tests check it against finite differences of
/// plant::ArmPlant::evaluateRhs. Offline (allocates), not @rt.

#include <Eigen/Core>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/design/lti.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/joint_params.hpp"

namespace fullarm::design {

/// What one joint moves, about its axis, with the rest of the arm locked at a posture.
/// Gravity torques have the sign of fullarm::arm's g(q) (the torque that holds the load).
struct JointLoad {
  double inertia_kgm2 = 0.05;   ///< link and outboard links (without the user's arm)
  double gravity_cos_nm = 0.0;  ///< g(q) = gravity_cos_nm cos q + gravity_sin_nm sin q
  double gravity_sin_nm = 0.0;
  double user_inertia_kgm2 = 0.0;  ///< the user's forearm mass at the cuff, about the axis
  double user_gravity_cos_nm = 0.0;
  double user_gravity_sin_nm = 0.0;
  double user_stiffness_nm_per_rad = 0.0;  ///< cuff spring in joint space, k |z x r|^2
  double user_damping_nms_per_rad = 0.0;   ///< cuff damper in joint space, b |z x r|^2
};

/// The joint's load from the arm model at `posture` (joint `joint_index` of the model), with
/// the user's arm (`user`, as plant::ArmPlant merges it: point mass on its link, Cartesian
/// spring and damper mapped through the cuff's point Jacobian) when the joint moves the cuff.
/// @throws core::ConfigError for an index or posture out of range.
[[nodiscard]] JointLoad jointLoadFromArm(const arm::ArmModel& model, const plant::UserArmParams& user, int joint_index,
                                         const Eigen::VectorXd& posture);

/// One joint plant: hydraulics and load. `include_user` couples the user's arm (mass, gravity,
/// spring, damper); without it the model is the bare device.
struct JointPlantModel {
  plant::JointParams joint;
  JointLoad load;
  bool include_user = true;
};

/// Index of each state in the joint's state vector (the layout of plant::ArmPlant for n = 1).
enum JointStateIndex : int { kSpool = 0, kSpoolRate = 1, kPressureA = 2, kPressureB = 3, kAngle = 4, kVelocity = 5 };
inline constexpr int kJointStates = 6;
using JointStateVector = Eigen::Matrix<double, kJointStates, 1>;

/// A trim point: q and qd given, spool and pressures solved so that the pressures and the
/// velocity are stationary (p_a' = p_b' = 0, qd' = 0, spool at rest).
struct OperatingPoint {
  double q_rad = 0.0;
  double qd_radps = 0.0;
  double tau_user_nm = 0.0;  ///< the user's own (active) torque held at the trim
  JointStateVector state = JointStateVector::Zero();
  double command = 0.0;      ///< valve voltage [V] or desired torque [N m] that holds it
  double tau_cell_nm = 0.0;  ///< load-cell torque at the trim
};

/// Solves the trim at (q, qd) by Newton's method on (spool, p_a, p_b); the user's cuff spring
/// rests at q.
/// @throws std::runtime_error if it does not converge or needs a saturated valve.
[[nodiscard]] OperatingPoint solveOperatingPoint(const JointPlantModel& model, double q_rad, double qd_radps = 0.0,
                                                 double tau_user_nm = 0.0);

/// Right-hand side of the joint (the equations of plant::ArmPlant::evaluateRhs for one joint,
/// cuff spring linear in q about `op.q_rad`): returns dx/dt; `tau_cell_nm` gets the load-cell
/// torque.
[[nodiscard]] JointStateVector jointRhs(const JointPlantModel& model, const OperatingPoint& op,
                                        const JointStateVector& x, double command, double tau_user_nm,
                                        double* tau_cell_nm = nullptr);

/// How Coulomb/Stribeck friction enters the linear model.
enum class FrictionLinearization {
  kViscousOnly,  ///< viscous term only: Coulomb friction is a dissipative sector nonlinearity
                 ///< left out (the conservative choice for stability; the default)
  kTangent,      ///< tangent of the smooth friction law at qd (the exact Jacobian of the RHS)
  /// Viscous term plus the steepest (negative) slope of the Stribeck decay,
  /// -(tau_s - tau_c) sqrt(2)/w_s e^{-1/2} at |qd| = w_s/sqrt(2): the negative damping the
  /// joint sees while it moves slowly through the Stribeck region (stick-slip).
  kStribeckWorst,
};

/// The steepest slope of the Stribeck term (tau_s - tau_c) exp(-(w/w_s)^2) over w >= 0
/// [N m s/rad] (<= 0; 0 without a Stribeck peak).
[[nodiscard]] double stribeckWorstSlope(const plant::FrictionParams& f) noexcept;

/// Outputs of the linear joint model.
enum JointOutputIndex : int { kOutAngle = 0, kOutVelocity = 1, kOutTorqueCell = 2 };
/// Inputs of the linear joint model.
enum JointInputIndex : int { kInCommand = 0, kInUserTorque = 1 };

/// The linear joint about a trim point.
struct JointLinearModel {
  /// Continuous; states JointStateIndex (deviations), inputs [command, tau_user], outputs
  /// [q, qd, tau_cell] (JointOutputIndex).
  StateSpace plant;
  OperatingPoint op;
  /// dg/dq of the device (without the user's arm) at q [N m/rad]: what a model-based gravity
  /// compensation subtracts.
  double device_gravity_slope_nm_per_rad = 0.0;
};

/// Linearises `model` at `op` (analytic Jacobian).
[[nodiscard]] JointLinearModel linearizeJoint(const JointPlantModel& model, const OperatingPoint& op,
                                              FrictionLinearization friction = FrictionLinearization::kViscousOnly);

}  // namespace fullarm::design
