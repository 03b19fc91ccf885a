#pragma once
/// @file
/// Conversion of an ArmModel to an orocos-kdl tree and chain, for users who want KDL's
/// solvers and for cross-checking fullarm's own kinematics and dynamics.

#include <kdl/chain.hpp>
#include <kdl/tree.hpp>
#include <string>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// KDL tree with root segment "world"; one fixed segment "<joint>_origin" (X_PL0) followed by a
/// RotZ segment named after the joint whose tip is the link frame and which carries the link
/// inertia, plus a fixed segment "tool" on the tool link. The base transform X_WB is the first
/// fixed segment "base". Gravity is not part of a KDL tree: pass model.gravity_W_mps2 to the
/// solvers.
[[nodiscard]] KDL::Tree toKdlTree(const ArmModel& model);

/// The KDL chain from "world" to the segment of `tip_joint` (arm joints and, if the tip is a
/// hand joint, its hand ancestors).
[[nodiscard]] KDL::Chain toKdlChain(const ArmModel& model, int tip_joint);

}  // namespace fullarm::arm
