#include "fullarm/accessibility/target.hpp"

#include <cmath>

#include "fullarm/core/config_error.hpp"

namespace fullarm::accessibility {

GraspTarget resolveTarget(const haptics::Scene& scene, const arm::ArmModel& model, std::string_view name) {
  if (scene.targets.empty()) {
    throw core::ConfigError(scene.source, "targets",
                            "the scene names no target (add a `targets:` list: docs/haptics.md, Scene files)");
  }
  const haptics::SceneTarget* t = name.empty() ? &scene.targets.front() : scene.target(name);
  if (t == nullptr) {
    std::string names;
    for (const haptics::SceneTarget& s : scene.targets) names += (names.empty() ? "" : ", ") + s.name;
    throw core::ConfigError(scene.source, "targets",
                            "no target '" + std::string(name) + "' in the scene (targets: " + names + ")");
  }
  const Eigen::Isometry3d X_WS = haptics::armBasePose(scene, model).inverse();
  GraspTarget g;
  g.name = t->name;
  g.object = t->object;
  g.object_index = scene.objectIndex(t->object);
  g.position_W_m = X_WS * t->position_S_m;
  g.approach_W = (X_WS.linear() * t->approach_S).normalized();
  g.push_W = (X_WS.linear() * t->push_S).normalized();
  return g;
}

Eigen::Matrix3d graspOrientation(const GraspTarget& target, double roll_rad) {
  const Eigen::Vector3d x = target.approach_W;
  Eigen::Vector3d y = Eigen::Vector3d::UnitZ().cross(x);
  if (y.norm() < 1e-6) y = Eigen::Vector3d::UnitY() - Eigen::Vector3d::UnitY().dot(x) * x;
  y.normalize();
  const Eigen::Vector3d z = x.cross(y);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = std::cos(roll_rad) * y + std::sin(roll_rad) * z;
  R.col(2) = x.cross(R.col(1));
  return R;
}

}  // namespace fullarm::accessibility
