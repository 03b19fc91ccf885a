#pragma once
/// @file
/// One technician of a population on one scene target: the technician's arm (segment lengths,
/// link radii; the shoulder where the scene puts the arm's base), reach in the three modes, then
/// the push along the target's push direction with and without bracing against the force the
/// task needs (docs/accessibility.md, "Population").
///
/// Reach repair: the nominal arm's paths (planned once per scene, target and mode) are the
/// starting point of every technician's reach. A nominal path is repaired on the technician's
/// arm (its goal re-solved by inverse kinematics from the nominal goal, at the same hand
/// orientation and swivel angle; every waypoint and edge re-checked; each invalid stretch
/// re-planned locally between the valid waypoints around it); where the repair fails, or the
/// nominal arm did not reach in that mode, the technician's reach is planned afresh (goal sweep
/// and planner). Everything random comes from the technician's own seed.

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "fullarm/accessibility/brace_search.hpp"
#include "fullarm/accessibility/human_strength.hpp"
#include "fullarm/accessibility/population.hpp"
#include "fullarm/accessibility/reach.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::accessibility {

/// Number of reach modes.
inline constexpr int kReachModes = 3;
/// The reach modes in the order outcomes list them: free, contact allowed, hand only.
inline constexpr std::array<ReachMode, kReachModes> kReachModeOrder = {ReachMode::kFree, ReachMode::kContactAllowed,
                                                                       ReachMode::kHandOnly};

/// What every technician of a population attempts: one target of one scene.
struct PopulationTask {
  const arm::ArmModel* model = nullptr;   ///< the nominal arm (must outlive the task)
  const haptics::Scene* scene = nullptr;  ///< the scene (must outlive the task)
  std::string target;                     ///< the scene target's name ("" for the first)
  haptics::HapticsParams params;          ///< the haptic rendering's parameters
  HumanArm human;                         ///< the nominal person's strength and weight
  ReachOptions reach;                     ///< limits, planner, budget; the seed is the nominal arm's
  long repair_iterations = 2000;          ///< planner budget of each locally re-planned stretch
  BraceSearchOptions brace;               ///< the brace search (its seed is replaced per technician)
  double required_force_n = 0.0;          ///< the push the task needs along the push direction [N]
};

/// The nominal arm's reach on the task: computed once, shared by every technician.
struct NominalReach {
  GraspTarget target;       ///< resolved for the nominal arm
  Eigen::VectorXd q_start;  ///< the scene's `rest` posture
  ReachStudy study;         ///< the three modes (seed task.reach.seed)
  /// The mode's result (free, contact allowed, hand only).
  [[nodiscard]] const ReachResult& result(ReachMode mode) const noexcept;
};

/// Plans the nominal arm's reach in the three modes.
/// @throws core::ConfigError for a scene without a `rest` posture or an unknown target;
///   ReachInputError / std::invalid_argument as studyReach
[[nodiscard]] NominalReach planNominalReach(const PopulationTask& task);

/// How a technician's reach in one mode was answered.
enum class ReachSource {
  kRepaired = 0,  ///< the nominal path, repaired on the technician's arm (verdict reachable)
  kFresh = 1,     ///< planned afresh: goal sweep and planner on the technician's arm
};
/// "repaired", "fresh".
[[nodiscard]] const char* reachSourceName(ReachSource source) noexcept;

/// A technician's reach in one mode.
struct TechnicianReach {
  ReachMode mode = ReachMode::kFree;
  Verdict verdict = Verdict::kUnknown;
  ReachSource source = ReachSource::kFresh;
  std::vector<Eigen::VectorXd> path;  ///< reachable: start to goal, full configurations
};

/// One technician's outcome on the task.
struct TechnicianOutcome {
  Technician technician;
  std::array<TechnicianReach, kReachModes> reach;  ///< in kReachModeOrder
  /// The push was analysed (contact-allowed reach reached the target).
  bool push_analysed = false;
  /// Largest push without bracing [N]: the better of the unbraced push at the reached grasp and
  /// at the brace posture; +infinity when no torque limit bounds it, NaN when the arm cannot
  /// hold the posture or the push was not analysed.
  double push_unbraced_n = std::numeric_limits<double>::quiet_NaN();
  /// Largest push with bracing [N] (the brace search's best), same conventions.
  double push_braced_n = std::numeric_limits<double>::quiet_NaN();
  bool push_unbraced_ok = false;  ///< reached (contact allowed) and push_unbraced_n >= the force
  bool push_braced_ok = false;    ///< reached (contact allowed) and push_braced_n >= the force
  /// The reach in `mode`.
  [[nodiscard]] const TechnicianReach& reachIn(ReachMode mode) const noexcept;
};

/// How a technician's reach is answered.
enum class ReachStrategy {
  kRepair,  ///< repair the nominal path where the nominal arm reached, else plan afresh
  kFresh,   ///< plan afresh in every mode (the reference repair is checked against)
};

/// Evaluates `technician` on the task: builds the technician's arm (technicianArm), collision
/// world and strength (technicianStrength), answers reach in the three modes by `strategy`, then,
/// when contact-allowed reach reaches, searches the brace posture at the reached grasp and
/// compares the pushes with the task's force. `seed` seeds the fresh planners, the repair's
/// local planners and the brace search: the outcome depends only on the task, the nominal
/// reach, the technician and the seed.
[[nodiscard]] TechnicianOutcome evaluateTechnician(const PopulationTask& task, const NominalReach& nominal,
                                                   const Technician& technician, std::uint32_t seed,
                                                   ReachStrategy strategy = ReachStrategy::kRepair);

/// Repairs `nominal_path` (a path of the nominal arm `nominal_model`, start to a grasp of
/// `target`) on `checker`'s arm in `mode`. The goal is re-solved by solveIk from the nominal goal
/// at the nominal goal's tool-link orientation and swivel angle; when that does not converge to a
/// valid goal, at the nearest valid of 34 neighbours (swivel 0, +-5, +-10, +-20 degrees, the hand
/// rolled 0, +-30, +-60 degrees about its pointing axis). The start is kept; every waypoint and
/// every edge is re-checked at the motion step of `options`, and each invalid stretch re-planned
/// by planBetween (budget `repair_iterations`, seed options.seed) between the valid waypoints
/// around it. The repaired path, or empty when no goal candidate is valid, the start is not
/// valid, or a stretch cannot be re-planned.
[[nodiscard]] std::vector<Eigen::VectorXd> repairPath(ReachChecker& checker, ReachMode mode, const GraspTarget& target,
                                                      const arm::ArmModel& nominal_model,
                                                      const std::vector<Eigen::VectorXd>& nominal_path,
                                                      const ReachOptions& options, long repair_iterations);

}  // namespace fullarm::accessibility
