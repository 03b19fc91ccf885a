#pragma once
/// @file
/// The arm reduced to a rigid-body tree of its active joints (rigid_body_dynamics.hpp): every
/// locked joint's link merged into the body of its nearest active ancestor, at configuration
/// time (allocates; not @rt).

#include <Eigen/Core>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/rigid_body_dynamics.hpp"

namespace fullarm::arm {

/// Builds the reduced model: active[k] is the arm-model index of body k's joint; locked joints
/// stay at `posture` (size model.numJoints()). Links that no active joint moves are dropped
/// (they cannot load an active joint).
/// @throws std::invalid_argument for an empty, repeated or out-of-range active list or a
/// posture of the wrong size.
[[nodiscard]] RigidBodyModel reduceArmModel(const ArmModel& model, const std::vector<int>& active,
                                            const Eigen::VectorXd& posture);

/// Body k's point `p_L` given in arm-model link `link`'s frame, in body frame coordinates, and the
/// body that carries it (-1: no active joint moves that link; the point is then fixed).
struct BodyPoint {
  int body = -1;
  Eigen::Vector3d p_B = Eigen::Vector3d::Zero();
};
/// Locates an arm-model link point on the reduced model (same `active` and `posture` as
/// reduceArmModel). @throws std::invalid_argument for a bad link index.
[[nodiscard]] BodyPoint reducePoint(const ArmModel& model, const std::vector<int>& active,
                                    const Eigen::VectorXd& posture, int link, const Eigen::Vector3d& p_L);

}  // namespace fullarm::arm
