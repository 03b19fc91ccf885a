#pragma once
/// @file
/// Human arm size (paper section 3.2.3): the DH lengths of the DTS can be varied, together with
/// the link geometry, to explore an environment with a different user's arm.

#include <filesystem>
#include <optional>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::arm {

/// Target segment lengths; unset fields keep the model's value.
struct ArmSize {
  std::optional<double> upper_arm_length_m;  ///< |d| of model.upper_arm_joint
  std::optional<double> forearm_length_m;    ///< |d| of model.forearm_joint
  std::optional<double> hand_length_m;       ///< |tool translation|
  std::optional<double> link_radius_scale;   ///< factor on every capsule radius
};

/// Segment lengths of a model, as an ArmSize with every field set.
[[nodiscard]] ArmSize armSizeOf(const ArmModel& model);

/// A copy of `model` with the segment lengths of `size`. A segment scaled by s = new/old has its
/// DH d, the z coordinates of its link geometry and centre of mass scaled by s (the link lies
/// along its z axis between -d and 0 in the modified-DH link frame); the hand scales the tool
/// translation, the hand link's geometry and centre of mass and the hand joints' origins.
/// Masses and inertias about the centre of mass are kept (the DTS itself does not change).
/// @throws core::ConfigError (key path `arm_size.<field>`) for a non-positive or non-finite length,
///         or a segment the model does not declare.
[[nodiscard]] ArmModel scaleArm(const ArmModel& model, const ArmSize& size);

/// Loads an arm-size file: keys upper_arm_length_m, forearm_length_m, hand_length_m,
/// link_radius_scale (each optional) under a top-level `arm_size` map.
/// @throws core::ConfigError
[[nodiscard]] ArmSize loadArmSize(const std::filesystem::path& file);

}  // namespace fullarm::arm
