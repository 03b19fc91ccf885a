// A population of technicians on one study scene (scenes/accessibility/env1.yaml, target rim,
// push 100 N): the nominal arm's reach once, then every technician's reach repaired or planned
// afresh and the push with and without bracing (fullarm::accessibility::evaluateTechnician), as a
// core sweep on 1 or 2 threads. Args: technicians, threads. The 1,000-technician runs are the
// figure of BENCHMARKS.md (target: at most 10 min wall on 2 cores); the 20-technician run proves
// the program works. Run on a quiet machine:
//   build/release/bench/access_population_bench --benchmark_filter='BM_Population/1000/'
// The mpirun ratio is measured with the command (BENCHMARKS.md, "Accessibility population").

#include <benchmark/benchmark.h>

#include <cstdint>
#include <span>
#include <string>

#include "fullarm/accessibility/population.hpp"
#include "fullarm/accessibility/population_reach.hpp"
#include "fullarm/arm/arm_scaling.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/sweep.hpp"
#include "fullarm/haptics/scene.hpp"

namespace acc = fullarm::accessibility;
namespace core = fullarm::core;
namespace haptics = fullarm::haptics;

namespace {

void BM_Population(benchmark::State& state) {
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  const haptics::Scene scene = haptics::loadScene(core::defaultScenePath("accessibility/env1.yaml"));
  acc::PopulationTask task;
  task.model = &model;
  task.scene = &scene;
  task.params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  task.human = acc::loadHumanArm(acc::defaultHumanArmPath(), model);
  task.required_force_n = 100.0;
  task.brace.contact_force_max_n = task.reach.limits.max_link_force_n;
  task.brace.penetration_max_m = task.reach.limits.max_skin_depth_m;
  acc::PopulationOptions population;
  population.technicians = state.range(0);
  const fullarm::arm::ArmSize size = fullarm::arm::armSizeOf(model);
  core::SweepSpec spec;
  spec.name = "technicians";
  spec.samples = population.technicians;
  spec.seed = population.seed;
  spec.values_per_sample = 2;
  std::int64_t repaired = 0;
  std::int64_t pushing = 0;
  for (auto _ : state) {
    const acc::NominalReach nominal = acc::planNominalReach(task);
    const core::SweepResults r = core::runSweep(
        spec, {},
        [&](std::int64_t sample, core::RandomStream& rng, std::span<double> out) {
          const acc::Technician t =
              acc::drawTechnician(population, sample, rng, *size.upper_arm_length_m, *size.forearm_length_m);
          const acc::TechnicianOutcome o =
              acc::evaluateTechnician(task, nominal, t, static_cast<std::uint32_t>(rng.next() >> 32U));
          int n = 0;
          for (const acc::TechnicianReach& m : o.reach) n += m.source == acc::ReachSource::kRepaired ? 1 : 0;
          out[0] = n;
          out[1] = o.push_braced_ok ? 1.0 : 0.0;
        },
        static_cast<int>(state.range(1)));
    repaired = 0;
    pushing = 0;
    for (std::size_t i = 0; i < r.sample.size(); ++i) {
      repaired += static_cast<std::int64_t>(r.row(i)[0]);
      pushing += static_cast<std::int64_t>(r.row(i)[1]);
    }
  }
  state.counters["repaired_mode_answers"] = static_cast<double>(repaired);
  state.counters["push_braced_ok"] = static_cast<double>(pushing);
  state.SetLabel("env1 rim, " + std::to_string(state.range(0)) + " technicians, " + std::to_string(state.range(1)) +
                 " threads");
}
BENCHMARK(BM_Population)->ArgsProduct({{20, 1000}, {1, 2}})->Iterations(1)->Unit(benchmark::kSecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
