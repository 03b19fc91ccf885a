// Scene targets (the `targets:` key of the haptics scene loader) and their errors, and the bad
// scenes the accessibility study must reject clearly.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "config_text.hpp"
#include "fullarm/accessibility/target.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::accessibility {
namespace {

std::filesystem::path sourceDir() {
  const char* dir = std::getenv("FULLARM_SOURCE_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::current_path();
}

std::filesystem::path env3() {
  return sourceDir() / "scenes/accessibility/env3.yaml";
}

// Parses `text` as if it were env3.yaml and expects a ConfigError whose message holds `what`.
void expectSceneError(const std::string& text, const std::string& what) {
  try {
    (void)haptics::parseScene(text, env3());
    ADD_FAILURE() << "no error; expected one mentioning: " << what;
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(TargetTest, SceneTargetIsReadAndPlacedInTheArmFrame) {
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  const haptics::Scene scene = haptics::loadScene(env3());
  ASSERT_EQ(scene.targets.size(), 2u);
  EXPECT_EQ(scene.targets[0].object, "handwheel");
  const GraspTarget t = resolveTarget(scene, model, "");
  EXPECT_EQ(t.name, "rim");
  EXPECT_EQ(t.object_index, scene.objectIndex("handwheel"));
  // Heading 0: W = S shifted so that the model's shoulder (X_WB) lands on shoulder_m.
  const Eigen::Vector3d expected = scene.targets[0].position_S_m - scene.shoulder_S_m + model.X_WB.translation();
  EXPECT_LT((t.position_W_m - expected).norm(), 1e-12);
  EXPECT_LT((t.approach_W - Eigen::Vector3d::UnitY()).norm(), 1e-12);
  EXPECT_LT((t.push_W - Eigen::Vector3d::UnitX()).norm(), 1e-12);
}

TEST(TargetTest, GraspOrientationPointsTheHandAlongTheApproach) {
  GraspTarget t;
  t.approach_W = Eigen::Vector3d(0.0, 1.0, 0.0);
  for (double roll : {-2.0, 0.0, 0.7}) {
    const Eigen::Matrix3d R = graspOrientation(t, roll);
    EXPECT_LT((R.col(0) - t.approach_W).norm(), 1e-12);
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
  }
  // Roll 0: y horizontal.
  EXPECT_NEAR(graspOrientation(t, 0.0).col(1).z(), 0.0, 1e-12);
}

TEST(TargetTest, TargetOutsideEveryObjectIsAClearError) {
  const std::string text = testing::fileText(env3());
  expectSceneError(testing::replacedFirst(text, "position_m: [0.0, 0.50, 1.25]", "position_m: [0.0, 0.50, 1.75]"),
                   "from the surface of its object 'handwheel'");
}

TEST(TargetTest, TargetErrorsNameTheKey) {
  const std::string text = testing::fileText(env3());
  expectSceneError(testing::replacedFirst(text, "object: handwheel", "object: wheel"), "no object 'wheel'");
  expectSceneError(testing::replacedFirst(text, "approach: [0.0, 1.0, 0.0]", "approach: [0.0, 0.0, 0.0]"),
                   "non-zero direction");
  expectSceneError(testing::replacedFirst(text, "    push: [0.0, 1.0, 0.0]\n", ""), "push");
  expectSceneError(
      testing::replacedFirst(text, "    push: [0.0, 1.0, 0.0]\n", "    push: [1.0, 0.0, 0.0]\n    grip: 1\n"), "grip");
}

TEST(TargetTest, MissingMeshIsAClearError) {
  const std::string text = testing::fileText(env3());
  expectSceneError(testing::replacedFirst(
                       text, "shape: {type: cylinder, radius_m: 0.015, length_m: 0.18, segments: 16, max_edge_m: 0.03}",
                       "shape: {type: mesh, file: meshes/no_such_valve.dae}"),
                   "no_such_valve.dae");
}

TEST(TargetTest, ImpossibleDimensionsAreAClearError) {
  const std::string text = testing::fileText(env3());
  // Tubes wider than half the surround: no opening left.
  expectSceneError(testing::replacedFirst(text, "bar_width_m: 0.03", "bar_width_m: 0.30"), "bar_width");
  expectSceneError(testing::replacedFirst(text, "radius_m: 0.12", "radius_m: -0.12"), "radius");
}

TEST(TargetTest, UnknownOrMissingTargetNamesTheTargets) {
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  const haptics::Scene scene = haptics::loadScene(env3());
  try {
    (void)resolveTarget(scene, model, "stem");
    ADD_FAILURE() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("targets: rim"), std::string::npos) << e.what();
  }
  haptics::Scene none = scene;
  none.targets.clear();
  EXPECT_THROW((void)resolveTarget(none, model, ""), core::ConfigError);
}

}  // namespace
}  // namespace fullarm::accessibility
