// The motion checks and the two-configuration planner that repair uses (reach.hpp): the motion
// step against the joint box's diagonal computed here, motionValid against a posture-by-posture
// check at a finer step, and planBetween's path against motionValid edge by edge.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <vector>

#include "fullarm/accessibility/reach.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::accessibility {
namespace {

std::filesystem::path sourceDir() {
  const char* dir = std::getenv("FULLARM_SOURCE_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::current_path();
}

struct Env3 {
  arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  haptics::Scene scene = haptics::loadScene(sourceDir() / "scenes/accessibility/env3.yaml");
  haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, model);
  haptics::HapticsParams params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  GraspTarget target = resolveTarget(scene, model, "");
  Eigen::VectorXd q_start = haptics::scenePosture(scene, "rest", model);
};

TEST(ReachMotionTest, MotionStepIsTheResolutionTimesTheArmJointBoxDiagonal) {
  const Env3 e;
  double sum = 0.0;
  for (int j = 0; j < 7; ++j) {
    const double span = e.model.upperLimits()[j] - e.model.lowerLimits()[j];
    sum += span * span;
  }
  EXPECT_NEAR(motionStep(e.model, 0.002), 0.002 * std::sqrt(sum), 1e-12);
  EXPECT_NEAR(motionStep(e.model, 0.01), 5.0 * motionStep(e.model, 0.002), 1e-12);
}

// A straight motion from the start to the elbow folded fully the other way: motionValid agrees
// with checking every posture at a quarter of its step, and a motion that ends in an invalid
// posture is invalid.
TEST(ReachMotionTest, MotionValidAgreesWithAFinerPostureByPostureCheck) {
  const Env3 e;
  ReachChecker checker(e.model, e.world, e.params, ReachLimits{}, e.target.object_index);
  const double step = motionStep(e.model, 0.002);
  const std::vector<Eigen::VectorXd> ends = [&] {
    std::vector<Eigen::VectorXd> out;
    for (int j = 0; j < 7; ++j) {
      for (const bool upper : {false, true}) {
        Eigen::VectorXd q = e.q_start;
        q[j] = upper ? e.model.upperLimits()[j] : e.model.lowerLimits()[j];
        out.push_back(q);
      }
    }
    return out;
  }();
  int valid = 0;
  int invalid = 0;
  for (const Eigen::VectorXd& b : ends) {
    const bool fine = [&] {
      const int n = static_cast<int>(std::ceil((b - e.q_start).norm() / (0.25 * step)));
      for (int k = 0; k <= n; ++k) {
        if (!checker.check(e.q_start + (b - e.q_start) * (static_cast<double>(k) / n)).valid(ReachMode::kFree)) {
          return false;
        }
      }
      return true;
    }();
    const bool coarse = motionValid(checker, ReachMode::kFree, e.q_start, b, step);
    // On these motions no violation is shorter than the step: both checks agree.
    EXPECT_EQ(coarse, fine) << "motion to joint limit " << valid + invalid;
    if (!checker.check(b).valid(ReachMode::kFree)) {
      EXPECT_FALSE(coarse);
    }
    (coarse ? valid : invalid) += 1;
  }
  EXPECT_GT(valid, 0);
  EXPECT_GT(invalid, 0);
}

// From the start to a valid posture the straight motion cannot reach (the elbow or the wrist
// turned to a joint limit through an object): planBetween goes around, every edge valid.
TEST(ReachMotionTest, PlanBetweenJoinsTwoValidPosturesWithValidEdges) {
  const Env3 e;
  ReachOptions options;
  ReachChecker checker(e.model, e.world, e.params, options.limits, e.target.object_index);
  const double step = motionStep(e.model, options.motion_resolution);
  Eigen::VectorXd goal;
  for (int j = 0; j < 7 && goal.size() == 0; ++j) {
    for (const double fraction : {0.0, 0.25, 0.75, 1.0}) {
      Eigen::VectorXd q = e.q_start;
      q[j] = e.model.lowerLimits()[j] + fraction * (e.model.upperLimits()[j] - e.model.lowerLimits()[j]);
      if (checker.check(q).valid(ReachMode::kFree) && !motionValid(checker, ReachMode::kFree, e.q_start, q, step)) {
        goal = q;
        break;
      }
    }
  }
  ASSERT_GT(goal.size(), 0) << "no valid posture behind an obstacle among the single-joint moves";
  const std::vector<Eigen::VectorXd> path = planBetween(checker, ReachMode::kFree, e.q_start, goal, options);
  ASSERT_GE(path.size(), 3U);  // not the straight motion
  EXPECT_EQ(path.front(), e.q_start);
  EXPECT_EQ(path.back(), goal);
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    EXPECT_TRUE(motionValid(checker, ReachMode::kFree, path[i], path[i + 1], step)) << "edge " << i;
  }
  EXPECT_THROW((void)planBetween(checker, ReachMode::kFree, e.q_start, Eigen::VectorXd::Zero(3), options),
               std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::accessibility
