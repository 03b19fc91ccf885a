#pragma once
/// @file
/// One haptic query: the global search of the arm against a collision world at one configuration,
/// and the rendering of its minima in one or more modes (spring forces, the tailored-Jacobian
/// contact torques of Eq. (1)-(2), per-link contact records), with the arm's gravity torques
/// computed once and kept apart from the contact torques. `fullarm haptics query` and the haptics
/// step of `fullarm demo` run it. Not real-time: it allocates, and times the search.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/minima.hpp"

namespace fullarm::haptics {

/// The global search strategies.
enum class SearchKind {
  kSnch,    ///< SnchGlobalSearch (spatialized normal cones)
  kBullet,  ///< BulletGlobalSearch (Bullet's broad phase and GJK, then SNCH's exact pair test)
};

/// A global search of `kind` for `world` (Bullet builds its shapes from the world's meshes; the
/// search must then run on that world).
/// @throws std::invalid_argument from BulletGlobalSearch for a world without link meshes
[[nodiscard]] std::unique_ptr<GlobalSearch> makeGlobalSearch(SearchKind kind, const CollisionWorld& world);

/// Tick period of a query's rendering [s]: the contact records cover one tick from reset.
inline constexpr double kQueryTick_s = 1e-3;

/// A query's minima rendered in one mode.
struct QueryRendering {
  /// Sized for `model` and `max_minima` minima (at least 1).
  QueryRendering(const arm::ArmModel& model, RenderMode mode, int max_minima);

  RenderMode mode;
  /// What computeContactForces and computeContactTorques leave: the force at each minimum
  /// (`f_W`, world) and whether it was rendered, the per-link records (`links`), the summed
  /// rendered force on each link (`link_force_W`, world), `active_springs` and `fault`.
  ContactData contact;
  Eigen::VectorXd tau_contact_nm;  ///< Eq. (1)-(2) summed over the rendered minima; zero on a fault [N m]
  Eigen::VectorXd tau_total_nm;    ///< tau_contact_nm + QueryResult::tau_gravity_nm [N m]
};

/// Outcome of renderQuery().
struct QueryResult {
  Eigen::VectorXd q_rad;                   ///< the configuration [rad]
  std::vector<Eigen::Isometry3d> X_WL;     ///< link frames at q_rad (a minimum's p_L is in its link's)
  std::string search;                      ///< name of the search that ran ("snch", "bullet")
  double search_ms = 0.0;                  ///< wall time of the global search [ms]
  std::vector<LocalMinimum> minima;        ///< the search's minima, sorted by (link, object, distance)
  Eigen::VectorXd tau_gravity_nm;          ///< g(q) of the arm model, the torque that holds it [N m]
  std::vector<QueryRendering> renderings;  ///< one per requested mode, in the order asked

  /// True when a rendering flagged a contact fault (its contact torques are then zero).
  [[nodiscard]] bool fault() const noexcept;
};

/// Forward kinematics at `q`, one global search with `params`' cutoff L and pruning radius r (its
/// minima do not depend on the mode), the gravity torques g(q) once, then for each of `modes`:
/// computeContactForces over one tick of kQueryTick_s from reset records and
/// computeContactTorques with `params` in that mode.
/// @param world  the scene's collision world (link meshes and objects)
/// @param search the global search to run (makeGlobalSearch)
/// @param params contact parameters; `params.mode` is replaced by each entry of `modes`
/// @param q      configuration [rad], size model.numJoints()
/// @param modes  rendering modes, at least one
/// @throws std::invalid_argument for a `q` of the wrong size or no mode
[[nodiscard]] QueryResult renderQuery(const arm::ArmModel& model, const CollisionWorld& world, GlobalSearch& search,
                                      const HapticsParams& params, const Eigen::VectorXd& q,
                                      std::span<const RenderMode> modes);

}  // namespace fullarm::haptics
