#pragma once
/// @file
/// The reach of an arm model: the hand points of seeded random postures drawn uniformly within
/// the joint ranges, and the largest shoulder-to-hand distance among them.

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Hand points of postures drawn within the joint ranges, and the reach they show.
struct ReachSample {
  Eigen::Vector3d shoulder_W = Eigen::Vector3d::Zero();  ///< origin of the first joint (shoulder centre) [m]
  std::vector<Eigen::Vector3d> hand_W;                   ///< hand point (tool origin) of each posture [m]
  double reach_m = 0.0;  ///< largest shoulder-to-hand distance over the postures (0 for none) [m]

  /// Number of drawn postures.
  [[nodiscard]] int numPostures() const noexcept { return static_cast<int>(hand_W.size()); }
};

/// Draws `samples` postures, each joint uniform on [min_rad, max_rad] of its limits, and records
/// the hand point of each (forward kinematics). Posture k is drawn from
/// core::RandomStream(seed, nameSlot("arm.reach"), k), so it depends on the seed and k alone:
/// the same seed gives the same postures, and a shorter run the first postures of a longer one.
/// @param samples number of postures (>= 0)
/// @param seed    seed of the draws
/// @throws std::invalid_argument if `samples` is negative
[[nodiscard]] ReachSample sampleReach(const ArmModel& model, int samples, std::uint64_t seed);

}  // namespace fullarm::arm
