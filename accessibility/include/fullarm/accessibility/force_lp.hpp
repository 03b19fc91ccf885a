#pragma once
/// @file
/// The force linear program: the largest push a person can apply to a target along its push
/// direction at one configuration, with the arm braced on the structure at its contacts.
///
/// Sign conventions (used throughout this module):
/// - f is the force the hand applies ON the target (world frame); the push is s = f . d along
///   the unit push direction d.
/// - At contact c the arm pushes ON the structure with lambda_c n_c, n_c the unit normal from
///   the link into the structure (a minimum's u_W); lambda_c >= 0: the arm may push on the
///   structure, never pull. With friction, the arm's force on the structure lies in the pyramid
///   spanned by n_c + mu t (t = +-t1, +-t2), inscribed in the cone of coefficient mu.
/// - tau is the torque the person's muscles apply at each joint, positive toward +q. Static
///   balance of the arm: tau = J_hand^T f + sum_c J_c^T n_c lambda_c + g_human(q), with
///   g_human = dV/dq (the torque that holds the arm), J point Jacobians (linear rows).
/// - Joint strength: tau_min(q) <= tau <= tau_max(q) (human_strength.hpp).
///
/// The hand force off the push axis: by default f = s d exactly (the hand only pushes along
/// d). With ForceLpOptions::off_axis_force_max_n > 0 the hand may also apply a force of at most
/// that much along each of two axes orthogonal to d (a grasp that holds the target sideways);
/// the program chooses it.

#include <Eigen/Core>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "fullarm/accessibility/human_strength.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/minima.hpp"

namespace fullarm::accessibility {

/// One contact of the arm with the structure.
struct ForceContact {
  Eigen::MatrixXd J_c;                             ///< linear point Jacobian, 3 x k (the program's joints)
  Eigen::Vector3d n_W = Eigen::Vector3d::UnitX();  ///< unit normal from the link into the structure
  int link = -1;                                   ///< arm-model link (for reports)
  int minimum = -1;                                ///< index of the minimum it came from (for reports)
};

/// The data of one program, over k joints (the person's joints).
struct ForceProblem {
  Eigen::MatrixXd J_hand;                                       ///< linear Jacobian of the hand point, 3 x k
  Eigen::Vector3d push_direction_W = Eigen::Vector3d::UnitX();  ///< unit push direction d
  std::vector<ForceContact> contacts;
  Eigen::VectorXd gravity_nm;  ///< g_human(q) on the k joints [N m]
  Eigen::VectorXd tau_min_nm;  ///< lower torque limits [N m] (<= tau_max)
  Eigen::VectorXd tau_max_nm;  ///< upper torque limits [N m]
};

/// CLP's algorithm (both give the same optimum; the benchmark compares them).
enum class LpAlgorithm { kDual, kPrimal };

/// Options of the program.
struct ForceLpOptions {
  double friction_mu = 0.0;           ///< 0: frictionless contacts (normal force only); else the pyramid
  double off_axis_force_max_n = 0.0;  ///< bound on each off-axis hand force component [N]; 0: f = s d
  LpAlgorithm algorithm = LpAlgorithm::kDual;
  /// Matrix entries at most this large are dropped before CLP sees them: rounding noise of the
  /// Jacobians, which CLP mishandles (an entry of 1e-17 made it report s = 0 as optimal).
  double drop_tolerance = 1e-12;
};

/// Outcome of the program.
enum class ForceStatus {
  kOptimal,       ///< push_n is the largest push
  kCannotHold,    ///< infeasible: the arm cannot even hold itself here (no push >= 0 is possible)
  kUnbounded,     ///< no torque limit binds the push (the push line runs through the joints)
  kSolverFailed,  ///< CLP stopped for another reason, or its optimum failed the optimality check (message says which)
};

/// Name of a status ("optimal", "cannot hold", "unbounded", "solver failed").
[[nodiscard]] const char* toString(ForceStatus status) noexcept;

/// A joint torque limit that the optimum reaches.
struct ActiveLimit {
  int joint = -1;     ///< index into the program's joints (0 .. k-1)
  bool upper = true;  ///< tau_max (true) or tau_min (false)
};

/// Per contact at the optimum.
struct ContactForce {
  double normal_n = 0.0;                              ///< lambda_c: the push on the structure along n_c [N]
  Eigen::Vector3d force_W = Eigen::Vector3d::Zero();  ///< whole force of the arm on the structure [N]
};

/// Result of solveForceLp(). push_n, hand_force_W, tau_nm and contacts are meaningful only
/// when status == kOptimal (NaN otherwise).
struct ForceLpResult {
  ForceStatus status = ForceStatus::kSolverFailed;
  double push_n = std::numeric_limits<double>::quiet_NaN();  ///< s* [N]
  Eigen::Vector3d hand_force_W = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::VectorXd tau_nm;           ///< muscle torques at the optimum [N m]
  std::vector<ActiveLimit> active;  ///< the limits that bind, in joint order
  std::vector<ContactForce> contacts;
  std::string message;  ///< CLP's status in words when not optimal
};

/// Tolerance on a torque for reporting a limit as active [N m].
inline constexpr double kActiveLimitTolerance_nm = 1e-6;

/// Solves max s subject to the balance and the limits (see the file comment) with CLP. An optimum
/// is reported only when it passes an optimality check made here (primal point within its bounds;
/// reduced costs of the row duals of the right sign at every bound); otherwise the problem is
/// solved again from scratch with the other simplex algorithm, and kSolverFailed reported if that
/// fails the check too.
/// @throws std::invalid_argument for inconsistent sizes, a non-unit push direction, a limit
///   pair with tau_min > tau_max, a negative mu or off-axis bound
[[nodiscard]] ForceLpResult solveForceLp(const ForceProblem& problem, const ForceLpOptions& options = {});

/// How contacts are taken from the haptics minima, and the program's options.
struct PushOptions {
  /// A minimum of a non-hand link closer than this is a contact the arm can brace on [m]
  /// (default: the haptics force threshold d_f of config/haptics.yaml).
  double contact_distance_m = 0.01;
  ForceLpOptions lp;
};

/// The program at configuration q: the hand point Jacobian, one contact per minimum of a
/// non-hand link with distance_m < options.contact_distance_m (point: the minimum's link point,
/// normal: its u_W), g_human(q) and the torque limits, over human.jointIndices().
/// @param fk forward kinematics at q (computeForwardKinematics already run)
[[nodiscard]] ForceProblem buildForceProblem(const arm::ArmModel& model, const HumanArm& human, const arm::ArmData& fk,
                                             const Eigen::Vector3d& push_direction_W,
                                             std::span<const haptics::LocalMinimum> minima, const PushOptions& options);

/// The push with and without bracing at one configuration.
struct PushAnalysis {
  ForceLpResult braced;    ///< with the contacts
  ForceLpResult unbraced;  ///< the same posture, no contacts
  std::vector<ForceContact> contacts;
  /// braced.push_n / unbraced.push_n when both are optimal and the unbraced push is > 0;
  /// +infinity when bracing makes a push possible that was not (unbraced cannot hold or is 0);
  /// NaN otherwise.
  double leverage = std::numeric_limits<double>::quiet_NaN();
};

/// buildForceProblem, then solveForceLp with and without the contacts.
[[nodiscard]] PushAnalysis analysePush(const arm::ArmModel& model, const HumanArm& human, const arm::ArmData& fk,
                                       const Eigen::Vector3d& push_direction_W,
                                       std::span<const haptics::LocalMinimum> minima, const PushOptions& options);

}  // namespace fullarm::accessibility
