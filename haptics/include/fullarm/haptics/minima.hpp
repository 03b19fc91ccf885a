#pragma once
/// @file
/// LocalMinimum: one tracked local minimum distance (LMD) between an arm link and an
/// environment object, and the paper's endpoint-radius pruning (DTS paper section 3.2.1).

#include <Eigen/Core>
#include <limits>
#include <span>
#include <vector>

#include "fullarm/haptics/tri_mesh.hpp"

namespace fullarm::haptics {

/// One local minimum distance between a link mesh and an object mesh.
///
/// Points are kept in the local frames of their meshes so a minimum stays meaningful while
/// the arm moves; u_W is refreshed by every query or local-descent step. The force on the
/// link pushes along -u_W (away from the object).
struct LocalMinimum {
  int link = -1;        ///< arm-model link index
  int object = -1;      ///< scene object index
  int tri_link = -1;    ///< triangle of the link mesh holding p_L; -1 for a capsule link
  int tri_object = -1;  ///< triangle of the object mesh holding p_O
  /// The link's feature: of its mesh, or for a capsule link its part (capsuleFeature: a cap or
  /// the cylinder).
  Feature feature_link;
  Feature feature_object;
  Eigen::Vector3d p_L = Eigen::Vector3d::Zero();  ///< closest point on the link, link frame [m]
  Eigen::Vector3d p_O = Eigen::Vector3d::Zero();  ///< closest point on the object, object frame [m]
  double distance_m = 0.0;
  /// Unit direction from the link point to the object point, world frame. When the meshes
  /// touch (distance 0) it is minus the object's feature pseudo-normal.
  Eigen::Vector3d u_W = Eigen::Vector3d::UnitX();
  /// Distance before the last local-descent step (NaN for a fresh minimum) [m]; lets the
  /// spring damping estimate the approach rate.
  double previous_distance_m = std::numeric_limits<double>::quiet_NaN();
};

/// True when two minima join the same link/object feature pair.
[[nodiscard]] inline bool sameFeaturePair(const LocalMinimum& a, const LocalMinimum& b) noexcept {
  return a.link == b.link && a.object == b.object && a.feature_link == b.feature_link &&
         a.feature_object == b.feature_object;
}

/// Endpoint-radius pruning, DTS paper section 3.2.1: candidates are visited closest first; a
/// candidate whose link endpoint AND object endpoint both lie within `radius_m` of the
/// endpoints of an accepted minimum of the same link/object pair (or of a `baseline` minimum)
/// is discarded; the others are accepted. Endpoints are compared in the local frames of the
/// link and the object, so no pose is needed. `candidates` is replaced by the accepted ones,
/// sorted by (link, object, distance).
/// @param radius_m pruning radius r [m]; 0 keeps every candidate
/// @param baseline minima already accepted (for example the tracked set); not modified
void pruneMinima(std::vector<LocalMinimum>& candidates, double radius_m, std::span<const LocalMinimum> baseline = {});

/// Hands a fresh global-search result to the tracked set (DTS paper section 3.2.1): fresh
/// minima with the same feature pair as a tracked one, or whose endpoints both fall within
/// `radius_m` of a tracked one's, are discarded; the rest are appended to `tracked` (and
/// become part of the baseline). Returns the number appended. Not @rt (may grow `tracked`).
int adoptGlobalMinima(std::vector<LocalMinimum>& tracked, std::vector<LocalMinimum> fresh, double radius_m);

}  // namespace fullarm::haptics
