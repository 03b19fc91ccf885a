// Reach in three modes on the five study environments (scenes/accessibility/env*.yaml): the
// verdicts each scene is designed for, determinism under a seed, and budget failures.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <stdexcept>
#include <string>

#include "fullarm/accessibility/reach.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::accessibility {
namespace {

std::filesystem::path sourceDir() {
  const char* dir = std::getenv("FULLARM_SOURCE_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::current_path();
}

struct Study {
  arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  haptics::Scene scene;
  haptics::CollisionWorld world;
  ReachProblem problem;

  explicit Study(int env) : Study(sourceDir() / ("scenes/accessibility/env" + std::to_string(env) + ".yaml")) {}
  explicit Study(const std::filesystem::path& file)
      : scene(haptics::loadScene(file)), world(haptics::makeCollisionWorld(scene, model)) {
    problem.model = &model;
    problem.world = &world;
    problem.params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
    problem.q_start = haptics::scenePosture(scene, "rest", model);
    problem.target = resolveTarget(scene, model, "");
  }
};

// The reached path ends at a grasp: forward kinematics of its last state puts the hand point on
// the target, and its first state is the start.
void expectPathGraspsTarget(const Study& s, const ReachResult& r) {
  ASSERT_FALSE(r.path.empty());
  EXPECT_LT((r.path.front() - s.problem.q_start).norm(), 1e-12);
  arm::ArmData fk(s.model);
  arm::computeForwardKinematics(s.model, fk, r.path.back());
  EXPECT_LT((fk.X_WT.translation() - s.problem.target.position_W_m).norm(), 1e-3);
}

TEST(ReachStudyTest, Environment2IsProvenUnreachableAndAHandOnlyFalsePositive) {
  Study s(2);
  const ReachStudy r = studyReach(s.problem, ReachOptions{});
  EXPECT_EQ(r.free.verdict, Verdict::kUnreachable) << r.free.reason;
  EXPECT_EQ(r.contact.verdict, Verdict::kUnreachable) << r.contact.reason;
  EXPECT_GT(r.contact.goals.solved, 50);  // the certificate covers many grasp postures
  EXPECT_EQ(r.contact.goals.valid, 0);
  EXPECT_EQ(r.hand_only.verdict, Verdict::kReachable) << r.hand_only.reason;
  EXPECT_TRUE(r.handOnlyFalsePositive());
  expectPathGraspsTarget(s, r.hand_only);
}

TEST(ReachStudyTest, Environment3IsReachableWithFreeClearance) {
  Study s(3);
  const ReachStudy r = studyReach(s.problem, ReachOptions{});
  ASSERT_EQ(r.free.verdict, Verdict::kReachable) << r.free.reason;
  expectPathGraspsTarget(s, r.free);
  for (double d : r.free.path_min_distance_m) EXPECT_GE(d, ReachLimits{}.clearance_margin_m);
  EXPECT_EQ(r.contact.verdict, Verdict::kReachable);
  EXPECT_FALSE(r.handOnlyFalsePositive());
}

// 1, 4, 5: no grasp posture keeps the free margin (the goal certificate), and contact-allowed
// reach finds a path whose links stay within the contact limits.
TEST(ReachStudyTest, Environments145NeedContact) {
  for (int env : {1, 4, 5}) {
    SCOPED_TRACE("environment " + std::to_string(env));
    Study s(env);
    const ReachStudy r = studyReach(s.problem, ReachOptions{});
    EXPECT_EQ(r.free.verdict, Verdict::kUnreachable) << r.free.reason;
    EXPECT_EQ(r.free.goals.valid, 0);
    ASSERT_EQ(r.contact.verdict, Verdict::kReachable) << r.contact.reason;
    expectPathGraspsTarget(s, r.contact);
    const ReachLimits lim;
    double touching = std::numeric_limits<double>::infinity();
    for (std::size_t l = 0; l < r.contact.links.size(); ++l) {
      EXPECT_GE(r.contact.path_min_distance_m[l], s.problem.params.force_threshold_m - lim.max_skin_depth_m - 1e-9);
      EXPECT_LE(r.contact.path_max_force_n[l], lim.max_link_force_n + 1e-9);
      touching = std::min(touching, r.contact.path_min_distance_m[l]);
    }
    EXPECT_LT(touching, s.problem.params.force_threshold_m);  // some link is in the skin: contact
  }
}

// The DRC valve scene's target (the hand point of its reach_valve posture): the arm gets there
// only with contact (the truss and the opening's frame), and the path ends on the target.
TEST(ReachStudyTest, DrcValveSceneTargetIsReachedWithContact) {
  Study s(sourceDir() / "scenes/valve_wall.yaml");
  EXPECT_EQ(s.problem.target.name, "wheel_rim");
  const ReachResult r = planReach(s.problem, ReachMode::kContactAllowed, ReachOptions{});
  ASSERT_EQ(r.verdict, Verdict::kReachable) << r.reason;
  expectPathGraspsTarget(s, r);
}

TEST(ReachStudyTest, SameSeedGivesTheSamePath) {
  Study s(4);
  ReachOptions o;
  o.seed = 7;
  const ReachResult a = planReach(s.problem, ReachMode::kContactAllowed, o);
  const ReachResult b = planReach(s.problem, ReachMode::kContactAllowed, o);
  ASSERT_EQ(a.verdict, Verdict::kReachable);
  ASSERT_EQ(a.path.size(), b.path.size());
  for (std::size_t i = 0; i < a.path.size(); ++i) EXPECT_EQ(a.path[i], b.path[i]);  // bit for bit
  EXPECT_EQ(a.iterations, b.iterations);
  o.planner = ReachPlanner::kSbl;
  const ReachResult c = planReach(s.problem, ReachMode::kContactAllowed, o);
  const ReachResult d = planReach(s.problem, ReachMode::kContactAllowed, o);
  ASSERT_EQ(c.path.size(), d.path.size());
  for (std::size_t i = 0; i < c.path.size(); ++i) EXPECT_EQ(c.path[i], d.path[i]);
}

TEST(ReachStudyTest, SblReachesTheFreeEnvironment) {
  Study s(3);
  ReachOptions o;
  o.planner = ReachPlanner::kSbl;
  const ReachResult r = planReach(s.problem, ReachMode::kFree, o);
  EXPECT_EQ(r.verdict, Verdict::kReachable) << r.reason;
  EXPECT_EQ(r.planner, "sbl");
}

TEST(ReachStudyTest, ExhaustedBudgetIsUnknownWithItsReason) {
  Study s(4);
  ReachOptions o;
  o.max_iterations = 3;
  const ReachResult r = planReach(s.problem, ReachMode::kContactAllowed, o);
  EXPECT_EQ(r.verdict, Verdict::kUnknown);
  EXPECT_LE(r.iterations, 3);
  EXPECT_NE(r.reason.find("budget of 3"), std::string::npos) << r.reason;
  EXPECT_TRUE(std::isfinite(r.closest_approach_m));
  EXPECT_GT(r.closest_approach_m, 0.0);
}

TEST(ReachStudyTest, BadLimitsAreRejected) {
  Study s(3);
  for (double bad : {std::nan(""), -1.0, std::numeric_limits<double>::infinity()}) {
    ReachOptions o;
    o.limits.max_link_force_n = bad;
    EXPECT_THROW((void)planReach(s.problem, ReachMode::kFree, o), std::invalid_argument);
  }
  ReachOptions o;
  o.limits.max_skin_depth_m = 0.02;  // deeper than d_f: touching
  EXPECT_THROW((void)planReach(s.problem, ReachMode::kFree, o), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::accessibility
