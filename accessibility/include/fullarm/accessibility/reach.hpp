#pragma once
/// @file
/// Reach in three modes: is there a path of the arm (shoulder fixed, joint limits respected)
/// from a start posture to a configuration whose hand grasps the target, when
///  - kFree: every link keeps at least the clearance margin from every object;
///  - kContactAllowed: links may touch and slide, with each link's rendered contact force (the
///    haptic rendering's springs, summed over the link's minima) at most max_link_force_n and
///    its depth into the rendered skin (d_f - d, d the exact link distance) at most
///    max_skin_depth_m;
///  - kHandOnly: only the hand's links keep the clearance margin, the others are ignored (what
///    hand-only haptics checks).
/// Distances are the haptics module's exact link distances (haptics::CollisionWorld), forces its
/// springs (haptics::computeContactForces). Planning is OMPL's RRT-Connect or SBL over the
/// seven arm joints, with budgets in planner iterations and a per-query seed, so a result does
/// not depend on the machine's load. Self-collision of the arm is not checked (the joint limits
/// keep the DTS links apart).

#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "fullarm/accessibility/ik.hpp"
#include "fullarm/accessibility/target.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"

namespace fullarm::accessibility {

/// The three validity rules.
enum class ReachMode { kFree, kContactAllowed, kHandOnly };
/// "free", "contact-allowed", "hand-only".
[[nodiscard]] const char* reachModeName(ReachMode mode) noexcept;

/// Bad limits or options of a reach query; the message names the field and the value.
class ReachInputError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// The limits of the three modes.
struct ReachLimits {
  /// Clearance every link keeps in free reach, and the hand's links in hand-only reach [m];
  /// default: the haptic force threshold d_f of config/haptics.yaml, so a free posture renders
  /// no force at all.
  double clearance_margin_m = 0.01;
  /// Largest rendered contact force on one link in contact-allowed reach [N] (the sum of the
  /// magnitudes of the link's spring forces): a light rest of the arm on a bar.
  double max_link_force_n = 40.0;
  /// Largest depth into the rendered skin in contact-allowed reach [m]: with d_f = 10 mm, 8 mm
  /// keeps every link at least 2 mm off the surface.
  double max_skin_depth_m = 0.008;
};

/// @throws ReachInputError naming the field for a non-finite or negative limit, or a skin
///   depth not below the force threshold `force_threshold_m` (the link would touch the surface)
void validateReachLimits(const ReachLimits& limits, double force_threshold_m);

/// The planners.
enum class ReachPlanner {
  kRrtConnect,  ///< OMPL RRT-Connect (bidirectional, uniform samples)
  kSbl,  ///< OMPL SBL (bidirectional, lazy collision checking) over a workspace projection: the wrist point, 5 cm cells
};
/// "rrt-connect", "sbl".
[[nodiscard]] const char* reachPlannerName(ReachPlanner planner) noexcept;

/// Settings of a query.
struct ReachOptions {
  ReachLimits limits;
  ReachPlanner planner = ReachPlanner::kRrtConnect;
  /// Planner iterations (termination-condition checks: one per tree extension) [-].
  long max_iterations = 20000;
  std::uint32_t seed = 1;  ///< seeds the query's sampler and planner (nothing else is random)
  /// Largest joint-space step between two checked states of a motion, as a fraction of the
  /// joint box's diagonal (OMPL's state validity checking resolution).
  double motion_resolution = 0.002;
  IkOptions ik;
};

/// One posture's distances and forces.
struct PostureCheck {
  std::vector<double>
      link_distance_m;  ///< per link, smallest exact distance to any object (inf: none within the search cutoff)
  std::vector<double> link_force_n;  ///< per link, summed magnitude of its rendered spring forces [N]
  bool valid_free = false;
  bool valid_contact = false;
  bool valid_hand_only = false;
  [[nodiscard]] bool valid(ReachMode mode) const noexcept;
};

/// Evaluates postures of the arm against a world: forward kinematics, one global search with a
/// cutoff above the clearance margin and d_f, the springs of the haptic rendering.
class ReachChecker {
 public:
  /// Keeps references to `model` and `world` (they must outlive it). `grasp_object`: the object
  /// the hand grasps (its minima with hand links are left out), -1 for none.
  ReachChecker(const arm::ArmModel& model, const haptics::CollisionWorld& world, const haptics::HapticsParams& params,
               const ReachLimits& limits, int grasp_object);
  /// The check of configuration `q` (full size).
  [[nodiscard]] PostureCheck check(const Eigen::VectorXd& q);
  /// Links with geometry that the search queries.
  [[nodiscard]] const std::vector<int>& geometryLinks() const noexcept { return links_; }
  /// Hand point of `q` [m], world.
  [[nodiscard]] Eigen::Vector3d handPoint(const Eigen::VectorXd& q);
  [[nodiscard]] const arm::ArmModel& model() const noexcept { return model_; }
  [[nodiscard]] const ReachLimits& limits() const noexcept { return limits_; }
  [[nodiscard]] long checks() const noexcept { return checks_; }
  /// The last check's minima (those of the hand with the grasped object left out), forward
  /// kinematics and rendered springs (ContactData::f_W and rendered, one per minimum).
  [[nodiscard]] const std::vector<haptics::LocalMinimum>& lastMinima() const noexcept { return minima_; }
  [[nodiscard]] const arm::ArmData& lastKinematics() const noexcept { return fk_; }
  [[nodiscard]] const haptics::ContactData& lastContact() const noexcept { return contact_; }

 private:
  const arm::ArmModel& model_;
  const haptics::CollisionWorld& world_;
  haptics::HapticsParams params_;
  ReachLimits limits_;
  arm::ArmData fk_;
  haptics::ContactData contact_;
  std::vector<haptics::LocalMinimum> minima_;
  std::vector<int> links_;
  int grasp_object_ = -1;
  double cutoff_m_ = 0.0;
  long checks_ = 0;
};

/// The three verdicts.
enum class Verdict { kReachable, kUnreachable, kUnknown };
/// "reachable", "unreachable", "unknown".
[[nodiscard]] const char* verdictName(Verdict verdict) noexcept;

/// The goal sweep behind a verdict: how many goal configurations were solved and how many are
/// valid in the mode; when none is, this is the certificate of an unreachable target.
struct GoalCertificate {
  int swivel_samples = 0;
  int roll_samples = 0;
  double swivel_step_deg = 0.0;
  double roll_step_deg = 0.0;
  int solved = 0;  ///< converged IK solutions within the joint limits
  int valid = 0;   ///< of those, valid in the mode
  /// The solved goal that came closest to valid: the link that failed, its distance [m] and
  /// rendered force [N] (empty link name when every goal was valid or none was solved).
  std::string closest_link;
  double closest_distance_m = std::numeric_limits<double>::quiet_NaN();
  double closest_force_n = std::numeric_limits<double>::quiet_NaN();
};

/// The outcome of one reach query in one mode.
struct ReachResult {
  ReachMode mode = ReachMode::kFree;
  Verdict verdict = Verdict::kUnknown;
  std::string reason;   ///< one sentence: why this verdict
  std::string planner;  ///< reachPlannerName of the planner that ran ("" when it did not run)
  long iterations = 0;  ///< planner iterations used
  /// Posture checks of this mode: the start's, the planner's and the path profile's (the goal
  /// sweep's, one per solved goal, are shared by the modes and not counted here).
  long checks = 0;
  GoalCertificate goals;
  /// Reachable: the path, start to goal, as planned (not smoothed), each a full configuration.
  std::vector<Eigen::VectorXd> path;
  /// Reachable: per link with geometry, the smallest distance and the largest rendered force
  /// along the path (checked at the motion resolution).
  std::vector<int> links;
  std::vector<double> path_min_distance_m;
  std::vector<double> path_max_force_n;
  /// Unknown: the smallest distance from the hand point to the target over the start tree [m].
  double closest_approach_m = std::numeric_limits<double>::quiet_NaN();
};

/// A reach problem: start posture and target in a world.
struct ReachProblem {
  const arm::ArmModel* model = nullptr;
  const haptics::CollisionWorld* world = nullptr;
  haptics::HapticsParams params;
  Eigen::VectorXd q_start;
  GraspTarget target;
};

/// Goal sweep (sweepGoalConfigurations from the start posture), then, when a valid goal exists,
/// the planner from the start to the valid goals within options.max_iterations.
/// Verdicts: kReachable with the path; kUnreachable when no solved goal is valid (the sweep's
/// resolution is the certificate's); kUnknown when the budget ran out (closest approach given)
/// or the start posture is not valid in the mode.
/// @throws ReachInputError for bad limits or options; std::invalid_argument for a start of the wrong
///   size or a problem without model or world
[[nodiscard]] ReachResult planReach(const ReachProblem& problem, ReachMode mode, const ReachOptions& options);

/// The joint-space step at which motions are checked: `motion_resolution` times the diagonal of
/// the arm joints' box (OMPL's state validity checking resolution over the seven arm joints) [rad].
[[nodiscard]] double motionStep(const arm::ArmModel& model, double motion_resolution);

/// Whether the straight joint-space motion from `a` to `b` (full configurations) is valid in
/// `mode`: both ends and the states between them at most `step_rad` apart are checked.
[[nodiscard]] bool motionValid(ReachChecker& checker, ReachMode mode, const Eigen::VectorXd& a,
                               const Eigen::VectorXd& b, double step_rad);

/// The planner of `options` (its seed, budget and motion resolution) from `from` to `to`, two
/// full configurations valid in `mode`, on `checker`'s arm and world: the path, `from` to `to`,
/// or empty when the budget ran out.
/// @throws ReachInputError for bad options; std::invalid_argument for configurations of the
///   wrong size
[[nodiscard]] std::vector<Eigen::VectorXd> planBetween(ReachChecker& checker, ReachMode mode,
                                                       const Eigen::VectorXd& from, const Eigen::VectorXd& to,
                                                       const ReachOptions& options);

/// The three modes on one problem, sharing the goal sweep.
struct ReachStudy {
  ReachResult free;
  ReachResult contact;
  ReachResult hand_only;
  /// Hand-only reach says reachable and contact-allowed reach proves it unreachable: the hand reaches where
  /// the arm could not be (a false positive of hand-only haptics).
  [[nodiscard]] bool handOnlyFalsePositive() const noexcept;
};

/// planReach in the three modes.
[[nodiscard]] ReachStudy studyReach(const ReachProblem& problem, const ReachOptions& options);

}  // namespace fullarm::accessibility
