#pragma once
/// @file
/// A fitted gravity set written as an arm YAML: the source arm file with each changed link's
/// `mass_kg`, `com_m` and `inertia_kgm2` lines rewritten, everything else (kinematics, limits,
/// actuators, sensors, comments) kept as it is.

#include <string>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::identification {

/// `yaml_text` (the arm YAML `source` was loaded from, named `source_name` in errors) with the
/// masses and centres of mass of `fitted`. A link whose mass or centre of mass changed gets them
/// at 10 significant digits with the comment `note`, and its inertia scaled by the mass ratio
/// (the same solid body with the new mass, so each line's "solid cylinder" comment stays true
/// in shape). Links that did not change keep their lines. A header comment names the source
/// file (by its file name only, so the text does not depend on where it was read) and `note`.
/// @throws std::invalid_argument naming the joint when a changed link's lines are not found, or
///   for models of different joints
[[nodiscard]] std::string armYamlWithGravity(std::string_view yaml_text, const std::string& source_name,
                                             const arm::ArmModel& source, const arm::ArmModel& fitted,
                                             std::string_view note);

}  // namespace fullarm::identification
