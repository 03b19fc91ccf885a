#include "fullarm/arm/arm_scaling.hpp"

#include <cmath>

#include "fullarm/core/config_error.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::arm {
namespace {

void requirePositive(const std::optional<double>& value, const char* field) {
  if (value && !(std::isfinite(*value) && *value > 0.0)) {
    throw core::ConfigError({}, std::string("arm_size.") + field,
                            "expected a finite value > 0, got " + std::to_string(*value));
  }
}

// Scale the segment carried by `joint`: its DH d and the z coordinates of its link's geometry
// and centre of mass (the link spans z in [-d, 0] of its modified-DH frame).
void scaleSegment(ArmModel& model, int joint, double s) {
  Joint& j = model.joints[static_cast<std::size_t>(joint)];
  j.dh->d_m *= s;
  j.X_PL0 = dhTransform(*j.dh);
  j.inertial.com_m.z() *= s;
  j.geometry.from_m.z() *= s;
  j.geometry.to_m.z() *= s;
}

}  // namespace

ArmSize armSizeOf(const ArmModel& model) {
  ArmSize size;
  if (model.upper_arm_joint >= 0) {
    size.upper_arm_length_m = std::abs(model.joints[static_cast<std::size_t>(model.upper_arm_joint)].dh->d_m);
  }
  if (model.forearm_joint >= 0) {
    size.forearm_length_m = std::abs(model.joints[static_cast<std::size_t>(model.forearm_joint)].dh->d_m);
  }
  size.hand_length_m = model.X_LT.translation().norm();
  size.link_radius_scale = 1.0;
  return size;
}

// §3.2.3: arm size through the DH parameters and the link geometry (reports/equations.md).
ArmModel scaleArm(const ArmModel& model, const ArmSize& size) {
  requirePositive(size.upper_arm_length_m, "upper_arm_length_m");
  requirePositive(size.forearm_length_m, "forearm_length_m");
  requirePositive(size.hand_length_m, "hand_length_m");
  requirePositive(size.link_radius_scale, "link_radius_scale");
  const ArmSize now = armSizeOf(model);
  ArmModel scaled = model;

  const auto scale_joint = [&](const std::optional<double>& target, const std::optional<double>& current, int joint,
                               const char* field) {
    if (!target) return;
    if (joint < 0 || !current || *current <= 0.0) {
      throw core::ConfigError(model.source, std::string("arm_size.") + field,
                              "the arm model declares no segment with a length to scale");
    }
    scaleSegment(scaled, joint, *target / *current);
  };
  scale_joint(size.upper_arm_length_m, now.upper_arm_length_m, model.upper_arm_joint, "upper_arm_length_m");
  scale_joint(size.forearm_length_m, now.forearm_length_m, model.forearm_joint, "forearm_length_m");

  if (size.hand_length_m) {
    if (!(*now.hand_length_m > 0.0)) {
      throw core::ConfigError(model.source, "arm_size.hand_length_m", "the arm model's tool has zero length");
    }
    const double s = *size.hand_length_m / *now.hand_length_m;
    scaled.X_LT.translation() *= s;
    Joint& hand = scaled.joints[static_cast<std::size_t>(model.tool_link)];
    hand.inertial.com_m *= s;
    hand.geometry.from_m *= s;
    hand.geometry.to_m *= s;
    for (Joint& j : scaled.joints) {
      if (j.is_hand && j.parent == model.tool_link) j.X_PL0.translation() *= s;
    }
  }
  if (size.link_radius_scale) {
    for (Joint& j : scaled.joints) j.geometry.radius_m *= *size.link_radius_scale;
  }
  validateArmModel(scaled);
  return scaled;
}

ArmSize loadArmSize(const std::filesystem::path& file) {
  const core::YamlMap root = core::YamlMap::load(file);
  const core::YamlMap m = root.map("arm_size");
  ArmSize size;
  size.upper_arm_length_m = m.optionalNumber("upper_arm_length_m", "metres");
  size.forearm_length_m = m.optionalNumber("forearm_length_m", "metres");
  size.hand_length_m = m.optionalNumber("hand_length_m", "metres");
  size.link_radius_scale = m.optionalNumber("link_radius_scale", "factor");
  m.finish();
  root.finish();
  const auto check = [&](const std::optional<double>& v, const char* key) {
    if (v && !(*v > 0.0)) m.fail(key, "expected a value > 0");
  };
  check(size.upper_arm_length_m, "upper_arm_length_m");
  check(size.forearm_length_m, "forearm_length_m");
  check(size.hand_length_m, "hand_length_m");
  check(size.link_radius_scale, "link_radius_scale");
  return size;
}

}  // namespace fullarm::arm
