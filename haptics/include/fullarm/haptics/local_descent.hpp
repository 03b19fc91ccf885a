#pragma once
/// @file
/// Local descent (Johnson, Willemsen & Cohen, HAPTICS 2004; DTS paper section 3.2.1): the 1 kHz
/// update that slides every tracked minimum to the nearby local minimum at the new poses by
/// walking across edges and vertex one-rings, between two global searches.

#include <span>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/minima.hpp"

namespace fullarm::haptics {

struct LocalDescentParams {
  /// Walk steps per minimum and tick (each step tests the triangles around both closest
  /// features); bounds the run time.
  int max_iterations = 16;
  /// A step is taken only if it lowers the distance by more than this [m] (strict decrease:
  /// no ping-pong between triangles sharing the closest edge).
  double min_decrease_m = 1e-12;
  /// Minima farther than this after the update are dropped [m] (infinity: keep all).
  double drop_beyond_m = std::numeric_limits<double>::infinity();
  /// Skip the evaluation of an object-side neighbour when the step's best pair so far already
  /// lies on a feature it shares and the first-order screening at that pair rejects it (exact:
  /// such a neighbour cannot lower the distance below the best). false runs every screened
  /// neighbour's triangle-pair query (the reference path of the tests).
  bool rescreen_neighbours = true;
  /// Before screening the neighbour triangles of a closest vertex or edge one by one, test the
  /// direction to the other mesh against the feature's precomputed rejection cone
  /// (neighbour_cones.hpp): inside it, every neighbour would fail the per-triangle screening,
  /// so none is looked at (exact). false screens every neighbour (the reference path of the
  /// tests).
  bool cone_screening = true;
};

struct LocalDescentStats {
  int steps = 0;                    ///< walk steps taken, all minima
  int minima_at_iteration_cap = 0;  ///< minima that stopped at max_iterations
  int merged = 0;                   ///< minima removed because another reached the same feature pair
  int dropped = 0;                  ///< minima removed by drop_beyond_m
  int evaluated = 0;                ///< neighbour triangle pairs evaluated (closest points computed)
  int rescreened = 0;               ///< neighbour evaluations skipped by re-screening at the step's best pair
  int cone_rejected = 0;            ///< feature neighbourhoods (one side of one step) rejected whole by a cone
  int screened = 0;                 ///< neighbour triangles screened one by one (first-order test)
};

/// Updates every minimum to the current link poses (fk.X_WL) and object poses of `world`:
/// recomputes its triangle pair, walks to neighbouring triangles while the distance strictly
/// decreases, then refreshes features, points, distance, u_W and previous_distance_m. Minima
/// that reach the same link/object feature pair are merged (the first is kept); survivors
/// are compacted to the front, in their original order.
/// @return number of minima kept (minima[0, n) are valid)
/// @rt (allocation-free; at most max_iterations steps per minimum, each O(feature valence))
int updateMinimaLocalDescent(const CollisionWorld& world, const arm::ArmData& fk, std::span<LocalMinimum> minima,
                             const LocalDescentParams& params, LocalDescentStats* stats = nullptr) noexcept;

}  // namespace fullarm::haptics
