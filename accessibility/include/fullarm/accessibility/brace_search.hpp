#pragma once
/// @file
/// The brace-posture search: from a configuration whose hand holds the target, move the arm
/// through its self-motion (the null space of the hand's pose task, joint limits respected) and
/// find the configuration where the person can push hardest along the target's push direction,
/// bracing the arm on the structure where its links touch it.
///
/// Each candidate is evaluated with one haptic query (haptics::renderQuery, full-arm rendering)
/// and the force program with and without its contacts (force_lp.hpp). A candidate is allowed
/// when every non-hand link's rendered contact force is at most F_c and its depth into the
/// rendered skin (the link record's depth_m, d_f - d) at most delta; the hand links hold the
/// target and are not checked. The search is deterministic for a seed and bounded by a number
/// of evaluations, not by time.

#include <Eigen/Core>
#include <cstdint>

#include "fullarm/accessibility/force_lp.hpp"
#include "fullarm/accessibility/human_strength.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"

namespace fullarm::accessibility {

/// Options of searchBracePosture().
struct BraceSearchOptions {
  int max_evaluations = 120;          ///< candidate postures evaluated (the start included)
  std::uint64_t seed = 1;             ///< seed of the local refinement's random steps
  double step_rad = 0.05;             ///< self-motion step of the sweep (joint-space norm) [rad]
  double contact_force_max_n = 30.0;  ///< F_c: largest rendered contact force per link [N]
  /// delta: largest depth of a link into the rendered skin, d_f - d [m]; below d_f, so a link
  /// never touches the object's surface (distance 0)
  double penetration_max_m = 0.008;
  double hand_position_tolerance_m = 1e-4;       ///< a candidate's hand stays this close to the target [m]
  double hand_orientation_tolerance_rad = 1e-3;  ///< and this close in orientation [rad]
  /// Contacts and program options; contact_distance_m is replaced by the haptics d_f.
  PushOptions push;
};

/// Result of searchBracePosture().
struct BraceSearchResult {
  Eigen::VectorXd q_start_rad;    ///< the start configuration
  PushAnalysis start;             ///< the push at the start
  Eigen::VectorXd q_best_rad;     ///< the configuration with the largest braced push (the start if none beats it)
  PushAnalysis best;              ///< the push there
  int evaluations = 0;            ///< candidates evaluated
  int rejected_contact = 0;       ///< candidates whose contact was not allowed (F_c or delta exceeded)
  int rejected_limits = 0;        ///< self-motion steps stopped by a joint limit or the hand's tolerance
  double max_hand_error_m = 0.0;  ///< largest hand position error over the evaluated candidates [m]
  /// The best braced push [N]; NaN when no evaluated candidate had an optimal program.
  [[nodiscard]] double bestPush() const noexcept { return best.braced.push_n; }
};

/// Searches the self-motion around `q_start` (hand on the target: its pose there is the task)
/// for the largest braced push along `push_direction_W`.
/// @param world  the scene's collision world, built for `model`
/// @param search a global search over `world` (haptics::makeGlobalSearch)
/// @param params haptics parameters (spring stiffness, d_f, cutoff) of the rendering
/// @throws std::invalid_argument for a `q_start` of the wrong size, outside the joint limits, or
///   a non-positive budget or step
[[nodiscard]] BraceSearchResult searchBracePosture(const arm::ArmModel& model, const HumanArm& human,
                                                   const haptics::CollisionWorld& world, haptics::GlobalSearch& search,
                                                   const haptics::HapticsParams& params, const Eigen::VectorXd& q_start,
                                                   const Eigen::Vector3d& push_direction_W,
                                                   const BraceSearchOptions& options = {});

}  // namespace fullarm::accessibility
