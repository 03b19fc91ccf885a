#include "tune_command.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "cli_values.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/job_pool.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/nonlinear_stage.hpp"
#include "fullarm/design/tuner.hpp"
#include "fullarm/design/validation.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::app {
namespace {

using controllers::GainsConfig;
using controllers::JointGains;
using design::TuningResult;

constexpr const char* kGainsFileName = "gains.yaml";
constexpr int kImpedancePoints = 80;

struct TuneRun {
  GainsConfig tuned;  // the whole gains file with the tuned joints replaced
  std::vector<TuningResult> results;
  std::vector<design::PreparedJoint> nominal;        // nominal model of each tuned joint
  std::vector<design::NonlinearStageResult> stages;  // empty when the stage is off
  // The contact goal (Eq. C6) of each joint's written gains on the linear stage's model set and
  // coupled grid, whether or not it was a hard goal.
  std::vector<design::CoupledGoal> contact;
  double wall_s = 0.0;
  bool pass = false;
};

// The joint model the tuner designs for: the plant's joint, its load at the default posture
// and the validation file's nominal user (joint space), as `fullarm validate` simulates it.
design::JointPlantModel jointModel(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                                   const design::ValidationConfig& validation, const std::string& name) {
  design::JointPlantModel jm;
  jm.joint = plant_config.joints[static_cast<std::size_t>(plant::findPlantJoint(plant_config, name))];
  plant::UserArmParams no_user;
  const int idx = model.jointIndex(jm.joint.name);
  jm.load = design::jointLoadFromArm(model, no_user, idx, model.defaultPosture());
  jm.load.user_inertia_kgm2 = validation.user.inertia_kgm2;
  jm.load.user_stiffness_nm_per_rad = validation.user.stiffness_nm_per_rad;
  jm.load.user_damping_nms_per_rad = validation.user.damping_nms_per_rad;
  jm.include_user = true;
  return jm;
}

TuneRun tuneArm(const arm::ArmModel& model, const plant::PlantConfig& plant_config, const GainsConfig& gains,
                const design::ValidationConfig& validation, std::vector<std::string> joints, const TuneOptions& o) {
  if (gains.controller != controllers::ControllerKind::kAdmittance) {
    throw core::ConfigError(
        gains.source, "controller",
        "fullarm tune tunes the admittance controller; got " + std::string(controllerKindName(gains.controller)));
  }
  if (joints.empty()) {
    for (const JointGains& g : gains.joints) joints.push_back(g.name);
  }
  std::vector<int> slots;
  for (const std::string& name : joints) slots.push_back(controllers::findGainsJoint(gains, name));
  design::LoopSetup setup;
  setup.control_period_s = gains.control_period_s;
  setup.delay_samples = validation.ranges.delay_min_samples;
  design::TunerOptions options;
  options.global_evaluations = o.global_evaluations;
  options.local_evaluations = o.local_evaluations;
  options.rounds = o.rounds;
  options.seed = o.seed;
  // The wall the tuner designs for is the one validate renders.
  design::TuningGoals goals;
  if (validation.wall.enabled) {
    goals.wall_stiffness_nm_per_rad = validation.wall.stiffness_nm_per_rad;
    goals.wall_damping_nms_per_rad = validation.wall.damping_nms_per_rad;
  }
  TuneRun run;
  run.results.resize(slots.size());
  run.nominal.resize(slots.size());
  if (o.nonlinear_rounds > 0) run.stages.resize(slots.size());
  run.contact.resize(slots.size());
  std::vector<design::JointPlantModel> models;
  for (int slot : slots) models.push_back(jointModel(model, plant_config, validation, gains.joints[slot].name));
  const auto start = std::chrono::steady_clock::now();
  // Each joint's tuning is self-contained and seeded, so the result does not depend on the thread
  // count or on the scheduling. One job per joint (its linear stage, then its nonlinear stage) on a
  // shared pool: a thread takes the next joint as soon as it is free, so a joint's nonlinear stage
  // starts as soon as its linear stage ends, and a thread that finds no joint left helps the
  // running nonlinear stages with their simulations (job_pool.hpp, docs/controllers.md "Scheduling
  // of tune"). The stage takes its runs in set order, so its result is the sequential one.
  std::vector<design::JointScenario> scenarios(slots.size());
  std::vector<design::LinearHardGoals> hard(slots.size());
  core::JobPool pool(o.threads);
  pool.run(static_cast<int>(slots.size()), [&](int i) {
    const auto k = static_cast<std::size_t>(i);
    const JointGains& initial = gains.joints[static_cast<std::size_t>(slots[k])];
    const double q = model.defaultPosture()[model.jointIndex(initial.name)];
    design::TunerOptions joint_options = options;
    // Seeded by the joint's place in the gains file, not in --joints: a joint's result does not
    // depend on which other joints are tuned with it.
    joint_options.seed = options.seed + static_cast<std::uint64_t>(slots[k]);
    // validate's scenario of this joint: its free move and detector set the coupled goal's
    // damping requirement (coupled_stability.hpp).
    scenarios[k] =
        design::validationScenario(design::makeJointScenario(model, plant_config, gains, initial.name), validation);
    design::TuningGoals joint_goals = goals;
    joint_goals.detector = design::detectorModelOf(scenarios[k]);
    joint_goals.detector.modal_amplitude = o.modal_amplitude;
    joint_goals.contact_detector = design::contactDetectorModelOf(scenarios[k]);
    joint_goals.contact_hard = o.contact_goal;
    run.results[k] = design::tuneJoint(models[k], q, initial, setup, joint_goals, design::TuningBounds{},
                                       validation.ranges, joint_options);
    run.nominal[k] = design::prepareJoint(models[k], design::solveOperatingPoint(models[k], q), setup);
    if (o.nonlinear_rounds > 0) {
      // The linear stage's hard goals on its final model set: the nonlinear stage prefers
      // candidates that meet them and says so when the written gains do not.
      hard[k].goals = joint_goals;
      design::LoopSetup goal_setup = setup;
      goal_setup.grid_points = joint_options.grid_points;
      for (const design::ModelVariation& v : run.results[k].model_set) {
        hard[k].models.push_back(design::prepareVariation(models[k], q, goal_setup, v));
      }
      hard[k].coupled_models = run.results[k].coupled_models;
      // Nonlinear verification on validate's closed-loop harness (nonlinear_stage.hpp).
      design::NonlinearStageOptions nl;
      nl.rounds = o.nonlinear_rounds;
      nl.seed = o.seed;
      nl.pool = &pool;
      run.stages[k] = design::refineNonlinear(scenarios[k], run.results[k].tuned, initial, validation.ranges,
                                              validation.linear, nl, &hard[k]);
    }
    // The contact goal of the written gains (reported whether or not it was a hard goal).
    std::vector<design::PreparedJoint> contact_models = run.results[k].coupled_models;
    if (o.nonlinear_rounds > 0) {
      contact_models.insert(contact_models.end(), hard[k].models.begin(), hard[k].models.end());
    } else {
      design::LoopSetup goal_setup = setup;
      goal_setup.grid_points = joint_options.grid_points;
      for (const design::ModelVariation& v : run.results[k].model_set) {
        contact_models.push_back(design::prepareVariation(models[k], q, goal_setup, v));
      }
    }
    run.contact[k] = design::evaluateCoupledContact(
        contact_models, o.nonlinear_rounds > 0 ? run.stages[k].gains : run.results[k].tuned,
        {joint_goals.wall_stiffness_nm_per_rad, joint_goals.wall_damping_nms_per_rad}, joint_goals.contact_detector);
  });
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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

nlohmann::json gainsJson(const JointGains& g) {
  return {{"inertia_kgm2", g.impedance.inertia_kgm2},
          {"damping_nms_per_rad", g.impedance.damping_nms_per_rad},
          {"stiffness_nm_per_rad", g.impedance.stiffness_nm_per_rad},
          {"lambda_per_s", g.sliding_mode.lambda_per_s},
          {"valve_bound_v", g.sliding_mode.valve_bound_v},
          {"boundary_layer_radps", g.sliding_mode.boundary_layer_radps}};
}

nlohmann::json goalsJson(const design::GoalValues& v) {
  return {{"peak_sensitivity", v.peak_sensitivity},
          {"spectral_radius", v.spectral_radius},
          {"min_real_loop", v.min_real_loop},
          {"min_real_impedance_nms_per_rad", v.min_real_impedance},
          {"rms_user_torque_nm", v.rms_user_torque_nm},
          {"wall_stiffness_error", v.wall_error},
          {"contact_spectral_radius", v.contact_spectral_radius},
          {"contact_detector_score", v.contact_detector_score},
          {"contact_mode_hz", v.contact_mode_hz},
          {"contact_mode_decay_per_s", v.contact_mode_decay_per_s},
          {"hard", v.hard},
          {"soft", v.soft},
          {"feasible", v.feasible()}};
}

// A sampled plant and user (a model of the set, or the sample of a failed run).
nlohmann::json sampleJson(const design::ModelVariation& m) {
  return {{"bulk_modulus_scale", m.bulk_modulus_scale},
          {"valve_gain_scale", m.valve_gain_scale},
          {"friction_scale", m.friction_scale},
          {"inertia_scale", m.inertia_scale},
          {"user_stiffness_nm_per_rad", m.user_stiffness_nm_per_rad},
          {"user_damping_nms_per_rad", m.user_damping_nms_per_rad},
          {"delay_samples", m.delay_samples}};
}

// The contact goal (Eq. C6) of the written gains: <= 1 met.
nlohmann::json contactJson(const design::CoupledGoal& c) {
  return {{"value", design::coupledGoalValue(c)},
          {"spectral_radius", c.spectral_radius},
          {"detector_score", c.detector_score},
          {"mode_hz", c.detector_hz},
          {"mode_decay_per_s", c.detector_decay_per_s}};
}

void addToReport(const TuneRun& run, reports::Report& report, const std::string& heading) {
  nlohmann::json joints = nlohmann::json::array();
  for (std::size_t k = 0; k < run.results.size(); ++k) {
    const TuningResult& r = run.results[k];
    nlohmann::json models = nlohmann::json::array();
    for (const design::ModelVariation& v : r.model_set) {
      models.push_back(sampleJson(v));
    }
    joints.push_back({{"joint", r.joint},
                      {"feasible", r.feasible},
                      {"verdict", r.verdict},
                      {"evaluations", r.evaluations},
                      {"initial_gains", gainsJson(r.initial)},
                      {"tuned_gains", gainsJson(r.tuned)},
                      {"initial_goals", goalsJson(r.initial_goals)},
                      {"tuned_goals", goalsJson(r.tuned_goals)},
                      {"model_set", models},
                      {"nlopt_results", r.nlopt_results},
                      {"contact_goal", contactJson(run.contact[k])}});
  }
  nlohmann::json stages = nlohmann::json::array();
  for (const design::NonlinearStageResult& st : run.stages) {
    const auto scoreJson = [](const design::NonlinearScore& sc) {
      // Each failed run with its sample.
      nlohmann::json failed = nlohmann::json::array();
      for (const design::FailedRun& f : sc.failed_runs) {
        nlohmann::json sample = sampleJson(f.sample);
        sample["index"] = f.sample.index;
        const nlohmann::json entry = {{"set_index", f.set_index}, {"failure", f.failure}, {"sample", sample}};
        failed.push_back(entry);
      }
      return nlohmann::json{{"failed_runs", failed},
                            {"linear_ok", sc.linear_ok},
                            {"failures", sc.failures},
                            {"runs", sc.runs},
                            {"mean_rms_user_torque_nm", sc.mean_rms_user_torque_nm},
                            {"linear_hard_goals_met", sc.linear_hard_met},
                            {"linear_hard", sc.linear_hard},
                            {"linear_hard_goal", sc.linear_hard_goal}};
    };
    const bool attempted = st.hard_feasible_attempt.runs > 0;
    stages.push_back(
        {{"joint", st.gains.name},
         {"verified", st.verified},
         {"linear_hard_goals_met", st.linear_hard_goals_met},
         {"verdict", st.verdict},
         {"gains", gainsJson(st.gains)},
         {"linear_optimum", scoreJson(st.linear_optimum)},
         {"start", scoreJson(st.start)},
         {"final", scoreJson(st.final_score)},
         {"hard_feasible_search", st.hard_feasible_search},
         // null where no restricted search was made and replaced (no made-up gains)
         {"hard_feasible_attempt", attempted ? scoreJson(st.hard_feasible_attempt) : nlohmann::json(nullptr)},
         {"hard_feasible_attempt_gains",
          attempted ? gainsJson(st.hard_feasible_attempt_gains) : nlohmann::json(nullptr)},
         {"check_failures", st.check_failures},
         {"evaluations", st.evaluations},
         {"simulations", st.simulations}});
  }
  report.results()["tune"] = {
      {"wall_time_s", run.wall_s}, {"pass", run.pass}, {"joints", joints}, {"nonlinear_stage", stages}};

  reports::Section& section = report.addSection(heading);
  section.addParagraph(
      "Gains tuned per joint in the spirit of MATLAB systune (docs/analysis.md): NLopt DIRECT-L then COBYLA on "
      "log-scaled J_m, B_m, K_m, B_o/eps and lambda (B_o kept), minimising the worst soft goal (RMS user torque "
      "to follow 0.25-2 Hz reference sines of 0.1 rad, normalised by 0.5 N m; rendered stiffness of the "
      "validation file's wall at 1 Hz within 20 %) subject to the hard goals Ms <= 1.7, spectral radius < 1 (free and "
      "in contact), "
      "Re L > -1 (saturation sector) on every model of the set, and coupled stability with the detector's damping "
      "requirement over the set and a grid of the validated users (K_h, B_h, inertia, delays 1-3; passivity "
      "Re Z >= 0 is reported, not required); the set "
      "grows by the worst-case model of the validation ranges after each round. Hard and soft values are "
      "normalised: <= 1 means met.");
  reports::Table table;
  table.caption = "Before (starting gains) and after tuning, worst model of the final set";
  table.columns = {"Joint",
                   "Verdict",
                   "J_m [kg m^2]",
                   "B_m [N m s/rad]",
                   "K_m [N m/rad]",
                   "B_o/eps [V s/rad]",
                   "lambda [1/s]",
                   "Ms",
                   "spectral radius",
                   "min Re Z [N m s/rad]",
                   "RMS user torque [N m]",
                   "hard",
                   "soft"};
  const auto row = [&](const TuningResult& r, bool tuned) {
    const JointGains& g = tuned ? r.tuned : r.initial;
    const design::GoalValues& v = tuned ? r.tuned_goals : r.initial_goals;
    table.rows.push_back({r.joint + (tuned ? " tuned" : " start"),
                          tuned ? (r.feasible ? "feasible" : "infeasible") : (v.feasible() ? "feasible" : "infeasible"),
                          g.impedance.inertia_kgm2, g.impedance.damping_nms_per_rad, g.impedance.stiffness_nm_per_rad,
                          g.sliding_mode.valve_bound_v / g.sliding_mode.boundary_layer_radps,
                          g.sliding_mode.lambda_per_s, v.peak_sensitivity, v.spectral_radius, v.min_real_impedance,
                          v.rms_user_torque_nm, v.hard, v.soft});
  };
  for (const TuningResult& r : run.results) {
    row(r, false);
    row(r, true);
  }
  table.significant_digits = 4;
  section.addTable(std::move(table));
  for (const TuningResult& r : run.results) section.addParagraph(r.verdict);
  if (!run.stages.empty()) {
    section.addParagraph(
        "Nonlinear verification stage (docs/analysis.md): each joint's linearly tuned gains and its starting gains "
        "are scored on a small seeded Monte-Carlo of validate's closed-loop harness (own sample stream); a compass "
        "search on B_m, B_o/eps and lambda then minimises failed runs (unstable or too sluggish to reach the wall), "
        "then RMS user torque; each round ends with a fresh check batch whose failed runs join the sample set. "
        "Where the starting gains violate a linear hard goal that the linear optimum meets, the search first runs "
        "from the linear optimum over hard-feasible gains only (J_m and K_m polled too) and falls back to the "
        "search above when that does not verify. The written gains are the stage's result.");
    reports::Table nt;
    nt.caption = "Nonlinear stage: failed runs on its sample set";
    nt.columns = {"Joint",
                  "Verified",
                  "B_m [N m s/rad]",
                  "B_o/eps [V s/rad]",
                  "linear optimum",
                  "start",
                  "final",
                  "check batches",
                  "RMS user torque [N m]",
                  "simulations",
                  "linear hard goals (written gains)"};
    for (const design::NonlinearStageResult& st : run.stages) {
      std::string checks;
      for (int c : st.check_failures) checks += (checks.empty() ? "" : ", ") + std::to_string(c);
      const auto fails = [](const design::NonlinearScore& sc) {
        return sc.linear_ok ? std::to_string(sc.failures) + " / " + std::to_string(sc.runs)
                            : std::string("linear fail");
      };
      nt.rows.push_back(
          {st.gains.name, st.verified ? "yes" : "no", st.gains.impedance.damping_nms_per_rad,
           st.gains.sliding_mode.valve_bound_v / st.gains.sliding_mode.boundary_layer_radps, fails(st.linear_optimum),
           fails(st.start), fails(st.final_score), checks, st.final_score.mean_rms_user_torque_nm,
           static_cast<double>(st.simulations),
           st.linear_hard_goals_met ? std::string("met") : "violated: " + st.final_score.linear_hard_goal});
    }
    nt.significant_digits = 4;
    section.addTable(std::move(nt));
    for (const design::NonlinearStageResult& st : run.stages) section.addParagraph(st.verdict);
  }

  reports::XyChart convergence;
  convergence.title = "Convergence per evaluation: best feasible objective and least hard-goal value";
  convergence.x_axis = {"Evaluation", "", false};
  convergence.y_axis = {"Normalised goal (worst soft / worst hard)", "", true};
  for (const TuningResult& r : run.results) {
    reports::Series s;
    s.name = r.joint;
    for (std::size_t i = 0; i < r.history.size(); ++i) {
      s.x.push_back(static_cast<double>(i + 1));
      s.y.push_back(r.history[i] > 0.0 ? r.history[i] : std::numeric_limits<double>::quiet_NaN());
    }
    convergence.series.push_back(std::move(s));
    reports::Series h;
    h.name = r.joint + " least hard-goal value";
    for (std::size_t i = 0; i < r.hard_history.size(); ++i) {
      h.x.push_back(static_cast<double>(i + 1));
      h.y.push_back(r.hard_history[i] > 0.0 && std::isfinite(r.hard_history[i])
                        ? r.hard_history[i]
                        : std::numeric_limits<double>::quiet_NaN());
    }
    convergence.series.push_back(std::move(h));
  }
  convergence.caption =
      "Per joint: the best feasible objective (gaps: no feasible point yet) and the smallest worst normalised hard "
      "goal found so far (<= 1: feasible; it stays above 1 on a joint the hard goals leave infeasible). Steps up where "
      "a worst-case model joins the set.";
  section.addLineChart(std::move(convergence));

  reports::XyChart impedance;
  impedance.title = "Rendered impedance in free motion |Z(f)|, nominal model: starting vs tuned gains";
  impedance.x_axis = {"Frequency", "Hz", true};
  impedance.y_axis = {"|Z|", "N·m·s/rad", true};
  const Eigen::VectorXd f = design::logspace(0.1, 200.0, kImpedancePoints);
  for (std::size_t k = 0; k < run.results.size(); ++k) {
    for (bool tuned : {false, true}) {
      reports::Series s;
      s.name = run.results[k].joint + (tuned ? " tuned" : " start");
      const JointGains& g = tuned ? run.results[k].tuned : run.results[k].initial;
      for (Eigen::Index i = 0; i < f.size(); ++i) {
        const double m = std::abs(design::renderedImpedance(run.nominal[k], g, {}, 2.0 * std::numbers::pi * f[i]));
        s.x.push_back(f[i]);
        s.y.push_back(std::isfinite(m) && m > 0.0 ? m : std::numeric_limits<double>::quiet_NaN());
      }
      impedance.series.push_back(std::move(s));
    }
  }
  section.addLineChart(std::move(impedance));
}

void writeText(const std::filesystem::path& path, const std::string& text) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream out(path);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

}  // namespace

CLI::App* addTuneCommand(CLI::App& app, TuneOptions& o) {
  CLI::App* tune = app.add_subcommand(
      "tune", "Tune the admittance gains per joint (NLopt, systune-style goals); write gains.yaml and a report");
  tune->add_option("--plant", o.plant_config, "Plant YAML (default: config/dts_plant.yaml)")->check(CLI::ExistingFile);
  tune->add_option("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)")
      ->check(CLI::ExistingFile);
  tune->add_option("--gains", o.gains, "Starting gains YAML (default: config/dts_tune_start.yaml); B_o is kept")
      ->check(CLI::ExistingFile);
  tune->add_option("--ranges", o.validation_config,
                   "User model and uncertainty ranges (default: config/dts_validation.yaml)")
      ->check(CLI::ExistingFile);
  tune->add_option("--joints", o.joints, "Joints to tune, e.g. EB,WR (default: all)")->delimiter(',');
  tune->add_option("--global-evals", o.global_evaluations, "Global-stage evaluations per round")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  tune->add_option("--local-evals", o.local_evaluations, "Local (COBYLA) evaluations per round")
      ->check(CLI::Range(0, 100000))
      ->capture_default_str();
  tune->add_option("--rounds", o.rounds, "Worst-case rounds")->check(CLI::Range(1, 20))->capture_default_str();
  tune->add_option("--seed", o.seed, "Seed of the worst-case search")->capture_default_str();
  tune->add_option("--threads", o.threads, "Worker threads (one joint each)")
      ->check(CLI::Range(1, 64))
      ->capture_default_str();
  tune->add_option("--nonlinear-rounds", o.nonlinear_rounds,
                   "Rounds of the nonlinear verification stage (0: linear stage only)")
      ->check(CLI::Range(0, 20))
      ->capture_default_str();
  tune->add_flag("--modal-amplitude,!--peak-speed-amplitude", o.modal_amplitude,
                 "Coupled goal: each mode's own speed amplitude after the free move (Eq. C5, the default) or "
                 "(--peak-speed-amplitude) the move's peak speed (Eq. C3, a bound)");
  tune->add_flag("--contact-goal", o.contact_goal,
                 "Make the contact goal (Eq. C6: every mode against the wall judged decaying by the contact hold's "
                 "detector) a hard goal of the linear stage; it is reported in summary.json either way");
  tune->add_option("--out", o.out_dir, "Output folder")->capture_default_str();
  return tune;
}

int runTune(const TuneOptions& o) {
  const arm::ArmModel model = arm::loadArmModel(configPathOr(o.arm_config, arm::defaultArmModelPath));
  const plant::PlantConfig plant_config =
      plant::loadPlantConfig(configPathOr(o.plant_config, plant::defaultPlantConfigPath), model);
  const GainsConfig gains =
      controllers::loadGainsConfig(configPathOr(o.gains, controllers::defaultTuneStartGainsPath), model);
  const design::ValidationConfig validation =
      design::loadValidationConfig(configPathOr(o.validation_config, design::defaultValidationConfigPath));
  const TuneRun run = tuneArm(model, plant_config, gains, validation, o.joints, o);
  const std::filesystem::path out(o.out_dir);
  writeText(out / kGainsFileName, controllers::formatGainsYaml(run.tuned));
  reports::Report report("tune", "Admittance gains tuned per joint");
  int feasible = 0;
  for (const TuningResult& r : run.results) feasible += r.feasible ? 1 : 0;
  int verified = 0;
  for (const design::NonlinearStageResult& st : run.stages) verified += st.verified ? 1 : 0;
  std::ostringstream headline;
  headline << feasible << " of " << run.results.size() << " joints meet every linear hard goal";
  int written_feasible = 0;
  for (const design::NonlinearStageResult& st : run.stages) written_feasible += st.linear_hard_goals_met ? 1 : 0;
  if (!run.stages.empty()) {
    headline << "; " << verified << " verified by the nonlinear stage; the written gains of " << written_feasible
             << " meet the linear hard goals";
  }
  report.setVerdict(run.pass, headline.str());
  report.addHeadlineNumber("joints_feasible", "Joints meeting the hard goals", feasible, "");
  report.addHeadlineNumber("wall_time_s", "Tuning wall time", run.wall_s, "s");
  report.addFile(kGainsFileName);
  addToReport(run, report, "Tuning");
  report.write(out);
  for (const TuningResult& r : run.results) std::cout << r.verdict << "\n";
  for (const design::NonlinearStageResult& st : run.stages) std::cout << st.verdict << "\n";
  std::cout << "Tuned gains: " << (std::filesystem::absolute(out) / kGainsFileName).string() << " (" << std::fixed
            << std::setprecision(1) << run.wall_s << " s)\n";
  return run.pass ? 0 : 1;
}

TuneDemoStep runTuneDemoStep(const arm::ArmModel& model, const std::filesystem::path& out_dir,
                             reports::Report& report) {
  const plant::PlantConfig plant_config = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  const GainsConfig gains = controllers::loadGainsConfig(controllers::defaultTuneStartGainsPath(), model);
  const design::ValidationConfig validation = design::loadValidationConfig(design::defaultValidationConfigPath());
  // `fullarm tune`'s own budget and start: the demo's tuned gains are the shipped dts_gains.yaml
  // (a smaller linear budget moved the linear optima and with them the nonlinear stage's result).
  const TuneOptions o;
  const TuneRun run = tuneArm(model, plant_config, gains, validation, {}, o);
  TuneDemoStep step;
  step.gains_file = out_dir / "tuned_gains.yaml";
  writeText(step.gains_file, controllers::formatGainsYaml(run.tuned));
  report.addFile("tuned_gains.yaml");
  addToReport(run, report, "Tune the admittance controller");
  int feasible = 0;
  for (const TuningResult& r : run.results) feasible += r.feasible ? 1 : 0;
  int verified = 0;
  for (const design::NonlinearStageResult& st : run.stages) verified += st.verified ? 1 : 0;
  std::ostringstream detail;
  int written_feasible = 0;
  for (const design::NonlinearStageResult& st : run.stages) written_feasible += st.linear_hard_goals_met ? 1 : 0;
  detail << feasible << " of " << run.results.size() << " joints meet the linear hard goals, " << verified
         << " verified by the nonlinear stage, written gains of " << written_feasible << " meet the linear hard goals, "
         << std::fixed << std::setprecision(1) << run.wall_s << " s wall";
  step.pass = run.pass;
  step.detail = detail.str();
  return step;
}

}  // namespace fullarm::app
