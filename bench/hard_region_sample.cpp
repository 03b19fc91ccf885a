// Diagnostic (docs/analysis.md "Contact damping (Eq. C6) and SFE's remaining conflict",
// "The hard-feasible region, sampled"): is there a
// point that meets every linear hard goal of `fullarm tune` and fails none of the nonlinear
// stage's runs? A global, deterministic sample instead of the stage's local search.
//
//   hard_region_sample [--contact-goal] [--soft-max X] JOINT N
//
// Rebuilds the linear stage's hard-goal models exactly as `fullarm tune` does (start gains
// config/dts_tune_start.yaml, tune's default budget and seed; the coupled goal with the modal
// amplitude, Eq. C5; with --contact-goal also Eq. C6), then takes the first N points of a Halton
// sequence (bases 2, 3, 5, 7, 11) over the log10 box of the nonlinear stage's search (J_m, B_m,
// K_m, B_o/eps, lambda: NonlinearStageOptions' limits), keeps those that meet every hard goal,
// and scores those whose worst soft goal is at most X (default 80; the linear optimum's is about
// 38, the shipped SFE gains' 67) on the stage's initial set (4 ring corners, 3 stress corners,
// 16 draws of the stage's stream), stopping each at its first failed run. Prints one line per
// scored point and a summary. Exit status 0; 2 for bad arguments; 1 when the configuration does
// not load. A point whose goals cannot be evaluated (eigenvalues that do not converge) is counted
// as unscorable, as the tuner treats it.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/design/coupled_stability.hpp"
#include "fullarm/design/nonlinear_stage.hpp"
#include "fullarm/design/tuner.hpp"
#include "fullarm/design/validation.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "ring_experiment.hpp"

namespace fc = fullarm::controllers;
namespace fd = fullarm::design;
namespace ft = fullarm::design::test;

namespace {

// The i-th element (i >= 1) of the van der Corput sequence in `base`.
double radicalInverse(int i, int base) {
  double f = 1.0, r = 0.0;
  while (i > 0) {
    f /= base;
    r += f * (i % base);
    i /= base;
  }
  return r;
}

int usage(const char* why) {
  std::fprintf(stderr, "hard_region_sample: %s\nusage: hard_region_sample [--contact-goal] [--soft-max X] JOINT N\n",
               why);
  return 2;
}

}  // namespace

int run(int argc, char** argv);

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "hard_region_sample: %s\n", e.what());
    return 1;
  }
}

int run(int argc, char** argv) {
  bool contact = false;
  double soft_max = 80.0;
  std::vector<std::string> args;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--contact-goal") {
      contact = true;
    } else if (a == "--soft-max") {
      if (i + 1 >= argc) return usage("--soft-max needs a value");
      char* end = nullptr;
      soft_max = std::strtod(argv[++i], &end);
      if (*end != '\0' || !(soft_max > 0.0)) return usage("--soft-max expects a positive number");
    } else if (!a.empty() && a[0] == '-') {
      return usage(("unknown option " + a).c_str());
    } else {
      args.push_back(a);
    }
  }
  if (args.size() != 2) return usage("expected JOINT and N");
  char* end = nullptr;
  const long n_points = std::strtol(args[1].c_str(), &end, 10);
  if (*end != '\0' || n_points < 1 || n_points > 10000000) return usage("N must be an integer in [1, 1e7]");

  const auto model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  const auto plant = fullarm::plant::loadPlantConfig(fullarm::plant::defaultPlantConfigPath(), model);
  const auto start = fc::loadGainsConfig(fc::defaultTuneStartGainsPath(), model);
  const auto validation = fd::loadValidationConfig(fd::defaultValidationConfigPath());
  const int slot = fc::findGainsJoint(start, args[0]);
  const fc::JointGains& initial = start.joints[static_cast<std::size_t>(slot)];

  // The linear stage as `fullarm tune` runs it (design/src/tune_arm.cpp).
  const fd::JointPlantModel jm = fd::tunerJointModel(model, plant, validation, initial.name);
  const double q = model.defaultPosture()[model.jointIndex(initial.name)];
  fd::LoopSetup setup;
  setup.control_period_s = start.control_period_s;
  setup.delay_samples = validation.ranges.delay_min_samples;
  const fd::JointScenario sc =
      fd::validationScenario(fd::makeJointScenario(model, plant, start, initial.name), validation);
  fd::TuningGoals goals;
  if (validation.wall.enabled) {
    goals.wall_stiffness_nm_per_rad = validation.wall.stiffness_nm_per_rad;
    goals.wall_damping_nms_per_rad = validation.wall.damping_nms_per_rad;
  }
  goals.detector = fd::detectorModelOf(sc);
  goals.detector.modal_amplitude = true;
  goals.contact_detector = fd::contactDetectorModelOf(sc);
  goals.contact_hard = contact;
  fd::TunerOptions options;
  const fd::TuningResult tr =
      fd::tuneJoint(jm, q, initial, setup, goals, fd::TuningBounds{}, validation.ranges, options);
  fd::LoopSetup goal_setup = setup;
  goal_setup.grid_points = options.grid_points;
  std::vector<fd::PreparedJoint> models;
  for (const fd::ModelVariation& v : tr.model_set) models.push_back(fd::prepareVariation(jm, q, goal_setup, v));

  // The stage's initial sample set and search box (nonlinear_stage.hpp).
  const fd::NonlinearStageOptions stage;
  std::vector<fd::ModelVariation> set = fd::ringCorners(validation.ranges);
  for (const fd::ModelVariation& c : fd::stressCorners(validation.ranges, stage.corner_user_fraction)) set.push_back(c);
  for (const fd::ModelVariation& s : fd::stageSamples(validation.ranges, 1, sc.joint_name, 0, stage.samples)) {
    set.push_back(s);
  }
  const double lo[5] = {std::log10(stage.min_inertia_kgm2), std::log10(stage.min_damping_nms_per_rad),
                        std::log10(stage.min_stiffness_nm_per_rad), std::log10(stage.min_gain_v_s_per_rad),
                        std::log10(stage.min_lambda_per_s)};
  const double hi[5] = {std::log10(stage.max_inertia_kgm2), std::log10(stage.max_damping_nms_per_rad),
                        std::log10(stage.max_stiffness_nm_per_rad), std::log10(stage.max_gain_v_s_per_rad),
                        std::log10(stage.max_lambda_per_s)};
  constexpr int kBases[5] = {2, 3, 5, 7, 11};

  std::printf(
      "%s: linear stage %s (soft %.2f); box log10 J_m [%g, %g], B_m [%g, %g], K_m [%g, %g], "
      "B_o/eps [%g, %g], lambda [%g, %g]; %zu runs per point; contact goal %s\n",
      initial.name.c_str(), tr.feasible ? "feasible" : "infeasible", tr.tuned_goals.soft, lo[0], hi[0], lo[1], hi[1],
      lo[2], hi[2], lo[3], hi[3], lo[4], hi[4], set.size(), contact ? "hard" : "off");
  long feasible = 0, scored = 0, passed = 0, unscorable = 0;
  std::map<std::string, int> first_failures;
  for (long i = 1; i <= n_points; ++i) {
    double x[5];
    for (int d = 0; d < 5; ++d) {
      x[d] = std::pow(10.0, lo[d] + (hi[d] - lo[d]) * radicalInverse(static_cast<int>(i), kBases[d]));
    }
    fc::JointGains g = initial;
    g.impedance = {x[0], x[1], x[2]};
    g.sliding_mode.lambda_per_s = x[4];
    g.sliding_mode.boundary_layer_radps = g.sliding_mode.valve_bound_v / x[3];
    fd::GoalValues v;
    try {
      v = fd::evaluateGoals(models, g, goals, tr.coupled_models);
    } catch (const std::runtime_error&) {
      ++unscorable;
      continue;
    }
    if (!v.feasible()) continue;
    ++feasible;
    if (v.soft > soft_max) continue;
    ++scored;
    const fd::NonlinearScore s =
        fd::scoreNonlinear(sc, g, set, validation.linear, validation.ranges.delay_max_samples, 0, nullptr, 2);
    const bool ok = s.linear_ok && s.failures == 0;
    passed += ok ? 1 : 0;
    std::string why = !s.linear_ok ? "validate's linear check" : ok ? "" : s.failed_runs.front().failure;
    why = why.substr(0, why.find(" ("));
    why = why.substr(0, why.find(':'));
    if (!ok) ++first_failures[why];
    std::printf("%7ld J_m %.4g B_m %.4g K_m %.4g B_o/eps %.4g lambda %.4g | Ms %.2f hard %.3f soft %.2f | %s%s\n", i,
                x[0], x[1], x[2], x[3], x[4], v.peak_sensitivity, v.hard, v.soft,
                ok ? "PASSES all runs" : "first failure: ", ok ? "" : why.c_str());
  }
  std::printf(
      "%ld points: %ld meet every hard goal, %ld of those with soft <= %g scored, %ld pass every run; %ld unscorable\n",
      n_points, feasible, scored, soft_max, passed, unscorable);
  for (const auto& [why, count] : first_failures) std::printf("  first failure %s: %d\n", why.c_str(), count);
  return 0;
}
