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
#include "exit_codes.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/design/linear_analysis.hpp"
#include "fullarm/design/tune_arm.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "output_files.hpp"

namespace fullarm::app {
namespace {

using controllers::GainsConfig;
using controllers::JointGains;
using design::TuningResult;

constexpr const char* kGainsFileName = "gains.yaml";
constexpr int kImpedancePoints = 80;

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

void addToReport(const design::ArmTuningResult& run, reports::Report& report, const std::string& heading) {
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

}  // namespace

CLI::App* addTuneCommand(CLI::App& app, TuneOptions& o, OptionTable& table) {
  CLI::App* tune = app.add_subcommand(
      "tune", "Tune the admittance gains per joint (NLopt, systune-style goals); write gains.yaml and a report");
  OptionDeclarer declare(*tune, table);
  declare.file("--plant", o.plant_config, "Plant YAML (default: config/dts_plant.yaml)");
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--gains", o.gains, "Starting gains YAML (default: config/dts_tune_start.yaml); B_o is kept");
  declare.file("--ranges", o.validation_config,
               "User model and uncertainty ranges (default: config/dts_validation.yaml)");
  declare.list("--joints", o.tuning.joints, "Joints to tune, e.g. EB,WR (default: all)");
  declare.integer("--global-evals", o.tuning.global_evaluations, "Global-stage evaluations per round", 1, 100000);
  declare.integer("--local-evals", o.tuning.local_evaluations, "Local (COBYLA) evaluations per round", 0, 100000);
  declare.integer("--rounds", o.tuning.rounds, "Worst-case rounds", 1, 20);
  declare.integer("--seed", o.tuning.seed, "Seed of the worst-case search", 0, 2147483647);
  declare.integer("--threads", o.tuning.threads, "Worker threads (one joint each)", 1, 64);
  declare.integer("--nonlinear-rounds", o.tuning.nonlinear_rounds,
                  "Rounds of the nonlinear verification stage (0: linear stage only)", 0, 20);
  declare.flag("--modal-amplitude,!--peak-speed-amplitude", o.tuning.modal_amplitude,
               "Coupled goal: each mode's own speed amplitude after the free move (Eq. C5, the default) or "
               "(--peak-speed-amplitude) the move's peak speed (Eq. C3, a bound)");
  declare.flag("--contact-goal", o.tuning.contact_goal,
               "Make the contact goal (Eq. C6: every mode against the wall judged decaying by the contact hold's "
               "detector) a hard goal of the linear stage; it is reported in summary.json either way");
  declare.folder("--out", o.out_dir, "Output folder")->capture_default_str();
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
  // Each joint named once, and known to the gains file (also "EB" against "R_EB").
  static_cast<void>(gainsJointNames(gains, o.tuning.joints, "--joints"));
  const design::ArmTuningResult run = design::tuneArm(model, plant_config, gains, validation, o.tuning);
  const std::filesystem::path out(o.out_dir);
  writeTextFile(out / kGainsFileName, controllers::formatGainsYaml(run.tuned));
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
  writeReport(report, out);
  for (const TuningResult& r : run.results) std::cout << r.verdict << "\n";
  for (const design::NonlinearStageResult& st : run.stages) std::cout << st.verdict << "\n";
  std::cout << "Tuned gains: " << (std::filesystem::absolute(out) / kGainsFileName).string() << " (" << std::fixed
            << std::setprecision(1) << run.wall_s << " s)\n";
  return run.pass ? kExitPass : kExitInconclusive;
}

TuneDemoStep runTuneDemoStep(const arm::ArmModel& model, const std::filesystem::path& out_dir, reports::Report& report,
                             core::Progress& progress) {
  const plant::PlantConfig plant_config = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  const GainsConfig gains = controllers::loadGainsConfig(controllers::defaultTuneStartGainsPath(), model);
  const design::ValidationConfig validation = design::loadValidationConfig(design::defaultValidationConfigPath());
  // `fullarm tune`'s own budget and start: the demo's tuned gains are the shipped dts_gains.yaml
  // (a smaller linear budget moved the linear optima and with them the nonlinear stage's result).
  design::ArmTuningOptions tuning;
  tuning.progress = &progress;
  const design::ArmTuningResult run = design::tuneArm(model, plant_config, gains, validation, tuning);
  TuneDemoStep step;
  step.gains_file = out_dir / "tuned_gains.yaml";
  writeTextFile(step.gains_file, controllers::formatGainsYaml(run.tuned));
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
