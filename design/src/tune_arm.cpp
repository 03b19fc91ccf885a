#include "fullarm/design/tune_arm.hpp"

#include <chrono>
#include <string>

#include "fullarm/core/config_error.hpp"
#include "fullarm/core/job_pool.hpp"

namespace fullarm::design {
namespace {

// A joint's model name without its side prefix ("R_EB" -> "EB"), as progress lines name joints.
std::string shortName(const std::string& name) {
  return name.starts_with("R_") ? name.substr(2) : name;
}

}  // namespace

JointPlantModel tunerJointModel(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                const ValidationConfig& validation, const std::string& name) {
  JointPlantModel jm;
  jm.joint = plant_config.joints[static_cast<std::size_t>(plant::findPlantJoint(plant_config, name))];
  const plant::UserArmParams no_user;
  const int idx = model.jointIndex(jm.joint.name);
  jm.load = jointLoadFromArm(model, no_user, idx, model.defaultPosture());
  jm.load.user_inertia_kgm2 = validation.user.inertia_kgm2;
  jm.load.user_stiffness_nm_per_rad = validation.user.stiffness_nm_per_rad;
  jm.load.user_damping_nms_per_rad = validation.user.damping_nms_per_rad;
  jm.include_user = true;
  return jm;
}

ArmTuningResult tuneArm(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                        const controllers::GainsConfig& gains, const ValidationConfig& validation,
                        const ArmTuningOptions& o) {
  if (gains.controller != controllers::ControllerKind::kAdmittance) {
    throw core::ConfigError(gains.source, "controller",
                            "fullarm tune tunes the admittance controller; got " +
                                std::string(controllers::controllerKindName(gains.controller)));
  }
  std::vector<std::string> joints = o.joints;
  if (joints.empty()) {
    for (const controllers::JointGains& g : gains.joints) joints.push_back(g.name);
  }
  std::vector<int> slots;
  for (const std::string& name : joints) slots.push_back(controllers::findGainsJoint(gains, name));
  LoopSetup setup;
  setup.control_period_s = gains.control_period_s;
  setup.delay_samples = validation.ranges.delay_min_samples;
  TunerOptions options;
  options.global_evaluations = o.global_evaluations;
  options.local_evaluations = o.local_evaluations;
  options.rounds = o.rounds;
  options.seed = o.seed;
  // The wall the tuner designs for is the one validate renders.
  TuningGoals goals;
  if (validation.wall.enabled) {
    goals.wall_stiffness_nm_per_rad = validation.wall.stiffness_nm_per_rad;
    goals.wall_damping_nms_per_rad = validation.wall.damping_nms_per_rad;
  }
  ArmTuningResult run;
  run.results.resize(slots.size());
  run.nominal.resize(slots.size());
  if (o.nonlinear_rounds > 0) run.stages.resize(slots.size());
  run.contact.resize(slots.size());
  std::vector<JointPlantModel> models;
  for (int slot : slots) models.push_back(tunerJointModel(model, plant_config, validation, gains.joints[slot].name));
  const auto start = std::chrono::steady_clock::now();
  // Each joint's tuning is self-contained and seeded, so the result does not depend on the thread
  // count or on the scheduling. One job per joint (its linear stage, then its nonlinear stage) on a
  // shared pool: a thread takes the next joint as soon as it is free, so a joint's nonlinear stage
  // starts as soon as its linear stage ends, and a thread that finds no joint left helps the
  // running nonlinear stages with their simulations (job_pool.hpp, docs/analysis.md "Scheduling
  // of tune"). The stage takes its runs in set order, so its result is the sequential one.
  std::vector<JointScenario> scenarios(slots.size());
  std::vector<LinearHardGoals> hard(slots.size());
  core::JobPool pool(o.threads);
  core::Progress& progress = core::progressOrQuiet(o.progress);
  progress.begin("tune", slots.size() * (o.nonlinear_rounds > 0 ? 2 : 1));
  pool.run(static_cast<int>(slots.size()), [&](int i) {
    const auto k = static_cast<std::size_t>(i);
    const controllers::JointGains& initial = gains.joints[static_cast<std::size_t>(slots[k])];
    const double q = model.defaultPosture()[model.jointIndex(initial.name)];
    // One seed for every joint: tuneJoint draws each joint's worst-case models from a stream keyed
    // by the joint's name, so a joint's result does not depend on which other joints are tuned.
    const TunerOptions& joint_options = options;
    // validate's scenario of this joint: its free move and detector set the coupled goal's
    // damping requirement (coupled_stability.hpp).
    scenarios[k] = validationScenario(makeJointScenario(model, plant_config, gains, initial.name), validation);
    TuningGoals joint_goals = goals;
    joint_goals.detector = detectorModelOf(scenarios[k]);
    joint_goals.detector.modal_amplitude = o.modal_amplitude;
    joint_goals.contact_detector = contactDetectorModelOf(scenarios[k]);
    joint_goals.contact_hard = o.contact_goal;
    run.results[k] =
        tuneJoint(models[k], q, initial, setup, joint_goals, TuningBounds{}, validation.ranges, joint_options);
    run.nominal[k] = prepareJoint(models[k], solveOperatingPoint(models[k], q), setup);
    progress.step(shortName(initial.name) + ": linear stage " +
                  (run.results[k].feasible ? "meets its hard goals" : "misses a hard goal"));
    if (o.nonlinear_rounds > 0) {
      // The linear stage's hard goals on its final model set: the nonlinear stage prefers
      // candidates that meet them and says so when the written gains do not.
      hard[k].goals = joint_goals;
      LoopSetup goal_setup = setup;
      goal_setup.grid_points = joint_options.grid_points;
      for (const ModelVariation& v : run.results[k].model_set) {
        hard[k].models.push_back(prepareVariation(models[k], q, goal_setup, v));
      }
      hard[k].coupled_models = run.results[k].coupled_models;
      // Nonlinear verification on validate's closed-loop harness (nonlinear_stage.hpp).
      NonlinearStageOptions nl;
      nl.rounds = o.nonlinear_rounds;
      nl.seed = o.seed;
      nl.pool = &pool;
      run.stages[k] = refineNonlinear(scenarios[k], run.results[k].tuned, initial, validation.ranges, validation.linear,
                                      nl, &hard[k]);
      progress.step(shortName(initial.name) + ": nonlinear stage " +
                    (run.stages[k].verified ? "verified" : "NOT verified"));
    }
    // The contact goal of the written gains (reported whether or not it was a hard goal).
    std::vector<PreparedJoint> contact_models = run.results[k].coupled_models;
    if (o.nonlinear_rounds > 0) {
      contact_models.insert(contact_models.end(), hard[k].models.begin(), hard[k].models.end());
    } else {
      LoopSetup goal_setup = setup;
      goal_setup.grid_points = joint_options.grid_points;
      for (const ModelVariation& v : run.results[k].model_set) {
        contact_models.push_back(prepareVariation(models[k], q, goal_setup, v));
      }
    }
    run.contact[k] = evaluateCoupledContact(
        contact_models, o.nonlinear_rounds > 0 ? run.stages[k].gains : run.results[k].tuned,
        {joint_goals.wall_stiffness_nm_per_rad, joint_goals.wall_damping_nms_per_rad}, joint_goals.contact_detector);
  });
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.end();
  run.tuned = gains;
  run.tuned.source.clear();
  run.pass = true;
  for (std::size_t k = 0; k < slots.size(); ++k) {
    if (run.stages.empty()) {
      run.tuned.joints[static_cast<std::size_t>(slots[k])] = run.results[k].tuned;
      run.pass = run.pass && run.results[k].feasible;
    } else {
      run.tuned.joints[static_cast<std::size_t>(slots[k])] = run.stages[k].gains;
      run.pass = run.pass && run.stages[k].verified;
    }
  }
  return run;
}

}  // namespace fullarm::design
