// One reachability query per reach mode on the study scenes (scenes/accessibility/env1..5.yaml),
// RRT-Connect beside SBL in the same run: each query is the goal sweep plus the planner with the
// default budget and seed (fullarm::accessibility::planReach), so the times include the sweep
// that a query cannot skip. Also the goal sweep alone. Run on a quiet machine (BENCHMARKS.md).

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <string>

#include "fullarm/accessibility/reach.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/haptics/scene.hpp"

namespace acc = fullarm::accessibility;
namespace haptics = fullarm::haptics;

namespace {

struct StudyScene {
  fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  haptics::Scene scene;
  haptics::CollisionWorld world;
  acc::ReachProblem problem;

  explicit StudyScene(int env)
      : scene(haptics::loadScene(fullarm::core::defaultScenePath("accessibility/env" + std::to_string(env) + ".yaml"))),
        world(haptics::makeCollisionWorld(scene, model)) {
    problem.model = &model;
    problem.world = &world;
    problem.params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
    problem.q_start = haptics::scenePosture(scene, "rest", model);
    problem.target = acc::resolveTarget(scene, model, "");
  }
};

const StudyScene& studyScene(int env) {
  static std::unique_ptr<StudyScene> scenes[6];
  if (!scenes[env]) scenes[env] = std::make_unique<StudyScene>(env);
  return *scenes[env];
}

// args: environment, mode (0 free, 1 contact allowed, 2 hand only), planner (0 RRT-Connect, 1 SBL)
void BM_ReachQuery(benchmark::State& state) {
  const StudyScene& s = studyScene(static_cast<int>(state.range(0)));
  const auto mode = static_cast<acc::ReachMode>(state.range(1));
  acc::ReachOptions options;
  options.planner = state.range(2) == 0 ? acc::ReachPlanner::kRrtConnect : acc::ReachPlanner::kSbl;
  acc::ReachResult r;
  for (auto _ : state) {
    r = acc::planReach(s.problem, mode, options);
    benchmark::DoNotOptimize(r);
  }
  state.SetLabel(std::string("env") + std::to_string(state.range(0)) + " " + acc::reachModeName(mode) + " " +
                 acc::reachPlannerName(options.planner) + ": " + acc::verdictName(r.verdict));
  state.counters["iterations"] = static_cast<double>(r.iterations);
  state.counters["checks"] = static_cast<double>(r.checks);
}
BENCHMARK(BM_ReachQuery)
    ->ArgsProduct({{1, 2, 3, 4, 5}, {0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->MinTime(0.5);

void BM_GoalSweep(benchmark::State& state) {
  const StudyScene& s = studyScene(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    benchmark::DoNotOptimize(acc::sweepGoalConfigurations(s.model, s.problem.target, s.problem.q_start, {}));
  }
}
BENCHMARK(BM_GoalSweep)->DenseRange(1, 5)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
