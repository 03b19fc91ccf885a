// One technician of a population on a study scene: reach repaired from the nominal arm's paths
// against reach planned afresh (the same verdicts), repaired paths re-validated independently on
// the technician's arm at half the planner's motion step, and the outcome's determinism.
#include "fullarm/accessibility/population_reach.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "fullarm/arm/arm_scaling.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::accessibility {
namespace {

std::filesystem::path sourceDir() {
  const char* dir = std::getenv("FULLARM_SOURCE_DIR");
  return dir != nullptr ? std::filesystem::path(dir) : std::filesystem::current_path();
}

struct Scenario {
  arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  haptics::Scene scene;
  PopulationTask task;
  NominalReach nominal;

  explicit Scenario(int env)
      : scene(haptics::loadScene(sourceDir() / ("scenes/accessibility/env" + std::to_string(env) + ".yaml"))) {
    task.model = &model;
    task.scene = &scene;
    task.params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
    task.human = loadHumanArm(defaultHumanArmPath(), model);
    task.required_force_n = 100.0;
    task.brace.max_evaluations = 30;
    task.brace.contact_force_max_n = task.reach.limits.max_link_force_n;
    task.brace.penetration_max_m = task.reach.limits.max_skin_depth_m;
    nominal = planNominalReach(task);
  }

  // Technicians of an even mix, and the two ends of the size range.
  std::vector<Technician> technicians(int drawn) const {
    PopulationOptions options;
    options.seed = 11;
    std::vector<Technician> t;
    for (int i = 0; i < drawn; ++i) t.push_back(drawTechnician(options, i, model));
    Technician small = t.front();
    small.index = drawn;
    small.upper_arm_m = 0.283;
    small.forearm_m = 0.218;
    Technician large = t.front();
    large.index = drawn + 1;
    large.upper_arm_m = 0.365;
    large.forearm_m = 0.295;
    const arm::ArmSize nominal_size = arm::armSizeOf(model);
    for (Technician* x : {&small, &large}) {
      x->link_radius_scale =
          std::sqrt(x->upper_arm_m / *nominal_size.upper_arm_length_m * x->forearm_m / *nominal_size.forearm_length_m);
      t.push_back(*x);
    }
    return t;
  }
};

// Every edge of `path` valid in `mode` on the technician's own arm and world (built here, not
// taken from the outcome), checked at `step_rad`; the path starts at the start posture and its
// hand ends on the target.
void expectValidPath(const Scenario& s, const Technician& t, ReachMode mode, const std::vector<Eigen::VectorXd>& path,
                     double step_rad) {
  const arm::ArmModel model = technicianArm(s.model, t);
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(s.scene, model);
  const GraspTarget target = resolveTarget(s.scene, model, "");
  ReachChecker checker(model, world, s.task.params, s.task.reach.limits, target.object_index);
  ASSERT_GE(path.size(), 2U);
  EXPECT_LT((path.front() - s.nominal.q_start).norm(), 1e-12);
  arm::ArmData fk(model);
  arm::computeForwardKinematics(model, fk, path.back());
  EXPECT_LT((fk.X_WT.translation() - target.position_W_m).norm(), 1e-3);
  const Eigen::VectorXd lo = model.lowerLimits();
  const Eigen::VectorXd hi = model.upperLimits();
  int states = 0;
  for (std::size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::VectorXd& a = path[i];
    const Eigen::VectorXd& b = path[i + 1];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / step_rad)));
    for (int k = 0; k <= n; ++k) {
      const Eigen::VectorXd q = a + (b - a) * (static_cast<double>(k) / n);
      for (int j = 0; j < 7; ++j) {
        ASSERT_GE(q[j], lo[j] - 1e-12);
        ASSERT_LE(q[j], hi[j] + 1e-12);
      }
      ASSERT_TRUE(checker.check(q).valid(mode))
          << "technician " << t.index << ", " << reachModeName(mode) << ": edge " << i << " state " << k << " of " << n;
      ++states;
    }
  }
  EXPECT_GT(states, static_cast<int>(path.size()));
}

void checkRepairAgainstFresh(int env, int drawn, int& repaired_total) {
  const Scenario s(env);
  const double fine_step = 0.5 * motionStep(s.model, s.task.reach.motion_resolution);
  for (const Technician& t : s.technicians(drawn)) {
    const auto seed = static_cast<std::uint32_t>(100 + t.index);
    const TechnicianOutcome repaired = evaluateTechnician(s.task, s.nominal, t, seed, ReachStrategy::kRepair);
    const TechnicianOutcome fresh = evaluateTechnician(s.task, s.nominal, t, seed, ReachStrategy::kFresh);
    for (ReachMode mode : kReachModeOrder) {
      const TechnicianReach& r = repaired.reachIn(mode);
      const TechnicianReach& f = fresh.reachIn(mode);
      EXPECT_EQ(f.source, ReachSource::kFresh);
      EXPECT_EQ(verdictName(r.verdict), std::string(verdictName(f.verdict)))
          << "env" << env << ", technician " << t.index << " (upper arm " << t.upper_arm_m << " m, forearm "
          << t.forearm_m << " m), " << reachModeName(mode);
      if (r.source == ReachSource::kRepaired) {
        ++repaired_total;
        EXPECT_EQ(r.verdict, Verdict::kReachable);
        expectValidPath(s, t, mode, r.path, fine_step);
      }
    }
    EXPECT_EQ(repaired.push_analysed, fresh.push_analysed);
  }
}

TEST(PopulationReachTest, RepairAgreesWithFreshPlanningOnEnvironment1) {
  int repaired = 0;
  checkRepairAgainstFresh(1, 3, repaired);
  EXPECT_GT(repaired, 0);  // the nominal arm reaches env1 with contact: its path is repaired
}

TEST(PopulationReachTest, RepairAgreesWithFreshPlanningOnEnvironment3) {
  int repaired = 0;
  checkRepairAgainstFresh(3, 2, repaired);
  EXPECT_GT(repaired, 0);
}

TEST(PopulationReachTest, SameTechnicianAndSeedGiveTheSameOutcome) {
  const Scenario s(1);
  const Technician t = s.technicians(1).front();
  const TechnicianOutcome a = evaluateTechnician(s.task, s.nominal, t, 5);
  const TechnicianOutcome b = evaluateTechnician(s.task, s.nominal, t, 5);
  for (std::size_t m = 0; m < kReachModes; ++m) {
    EXPECT_EQ(a.reach[m].verdict, b.reach[m].verdict);
    ASSERT_EQ(a.reach[m].path.size(), b.reach[m].path.size());
    for (std::size_t i = 0; i < a.reach[m].path.size(); ++i) EXPECT_EQ(a.reach[m].path[i], b.reach[m].path[i]);
  }
  EXPECT_EQ(a.push_braced_n, b.push_braced_n);
  EXPECT_EQ(a.push_unbraced_n, b.push_unbraced_n);
}

// A path with an invalid waypoint is repaired around it: the stretch between the valid waypoints
// on either side is re-planned, and the result is valid.
TEST(PopulationReachTest, RepairReplansAnInvalidStretch) {
  const Scenario s(1);
  const ReachResult& nominal = s.nominal.result(ReachMode::kContactAllowed);
  ASSERT_EQ(nominal.verdict, Verdict::kReachable) << nominal.reason;
  const Technician t = s.technicians(1).front();
  const arm::ArmModel model = technicianArm(s.model, t);
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(s.scene, model);
  const GraspTarget target = resolveTarget(s.scene, model, "");
  ReachChecker checker(model, world, s.task.params, s.task.reach.limits, target.object_index);
  // A detour through a grasp posture whose arm is in the structure (the first goal of the
  // technician's goal sweep that is not valid with contact allowed), just before the goal.
  Eigen::VectorXd detour;
  for (const IkSolution& g : sweepGoalConfigurations(model, target, s.nominal.q_start, s.task.reach.ik)) {
    if (!checker.check(g.q_rad).valid(ReachMode::kContactAllowed)) {
      detour = g.q_rad;
      break;
    }
  }
  ASSERT_GT(detour.size(), 0);
  std::vector<Eigen::VectorXd> path = nominal.path;
  ASSERT_GE(path.size(), 2U);
  path.insert(path.end() - 1, detour);
  ASSERT_FALSE(checker.check(detour).valid(ReachMode::kContactAllowed));
  const std::vector<Eigen::VectorXd> repaired =
      repairPath(checker, ReachMode::kContactAllowed, target, s.model, path, s.task.reach, 5000);
  ASSERT_FALSE(repaired.empty());
  for (const Eigen::VectorXd& q : repaired) EXPECT_GT((q - detour).norm(), 1e-9) << "the invalid waypoint was kept";
  expectValidPath(s, t, ReachMode::kContactAllowed, repaired, motionStep(model, s.task.reach.motion_resolution));
}

}  // namespace
}  // namespace fullarm::accessibility
