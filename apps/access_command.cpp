#include "access_command.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli_values.hpp"
#include "exit_codes.hpp"
#include "fullarm/accessibility/brace_search.hpp"
#include "fullarm/accessibility/force_lp.hpp"
#include "fullarm/accessibility/human_strength.hpp"
#include "fullarm/accessibility/reach.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/query.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/reports/report.hpp"
#include "output_files.hpp"
#include "run_replay3d.hpp"

namespace fullarm::app {
namespace {

using accessibility::ReachResult;
using accessibility::Verdict;

// Distance for tables: none within the search cutoff is shown as NaN-free text.
double finiteOrNegative(double d) {
  return std::isfinite(d) ? d * 1e3 : -1.0;
}

nlohmann::json resultJson(const arm::ArmModel& model, const ReachResult& r) {
  nlohmann::json j;
  j["verdict"] = accessibility::verdictName(r.verdict);
  j["reason"] = r.reason;
  j["planner"] = r.planner;
  j["iterations"] = r.iterations;
  j["checks"] = r.checks;
  j["goals"] = {{"swivel_samples", r.goals.swivel_samples},
                {"roll_samples", r.goals.roll_samples},
                {"solved", r.goals.solved},
                {"valid", r.goals.valid}};
  if (!r.goals.closest_link.empty()) {
    j["goals"]["closest_link"] = r.goals.closest_link;
    j["goals"]["closest_distance_m"] = r.goals.closest_distance_m;
    j["goals"]["closest_force_n"] = r.goals.closest_force_n;
  }
  if (std::isfinite(r.closest_approach_m)) j["closest_approach_m"] = r.closest_approach_m;
  if (r.verdict == Verdict::kReachable) {
    nlohmann::json path = nlohmann::json::array();
    for (const Eigen::VectorXd& q : r.path) path.push_back(std::vector<double>(q.data(), q.data() + 7));
    j["path_q_rad"] = path;
    nlohmann::json links = nlohmann::json::array();
    for (std::size_t l = 0; l < r.links.size(); ++l) {
      links.push_back(
          {{"link", model.joints[static_cast<std::size_t>(r.links[l])].name},
           {"min_distance_m", std::isfinite(r.path_min_distance_m[l]) ? nlohmann::json(r.path_min_distance_m[l])
                                                                      : nlohmann::json(nullptr)},
           {"max_force_n", r.path_max_force_n[l]}});
    }
    j["links"] = links;
  }
  return j;
}

constexpr double kReplayStep_rad = 0.02;  // joint-space step between replay frames

std::array<double, 3> toArray(const Eigen::Vector3d& v) {
  return {v.x(), v.y(), v.z()};
}

// The 3D replay of a reached path: the arm's capsule links along the path (interpolated at
// kReplayStep_rad), the scene's meshes, the minima as lines coloured by their spring force,
// links inside the haptic skin highlighted, the contact torques as bars.
reports::Replay3d pathReplay(const accessibility::ReachProblem& p, const haptics::Scene& scene,
                             const accessibility::ReachLimits& limits, const ReachResult& r) {
  const arm::ArmModel& model = *p.model;
  accessibility::ReachChecker checker(model, *p.world, p.params, limits, p.target.object_index);
  reports::Replay3d replay;
  replay.title = std::string("3D replay: the ") + accessibility::reachModeName(r.mode) + " path to the target";
  replay.caption = "Frames follow the planned path at " + std::to_string(kReplayStep_rad) +
                   " rad steps (the time axis is the frame count at 25 frames per second, not a motion's timing).";
  for (int i = 0; i < p.world->numObjects(); ++i) {
    const haptics::CollisionObject& object = p.world->object(i);
    replay.meshes.push_back(replayMesh(scene.objects[static_cast<std::size_t>(i)].name, object.mesh, object.X_WO));
  }
  const std::vector<int> links = addReplayCapsuleLinks(model, replay);
  for (int j = 0; j < model.numArmJoints(); ++j)
    replay.joints.push_back(model.joints[static_cast<std::size_t>(j)].name);
  std::vector<Eigen::VectorXd> qs;
  for (std::size_t i = 0; i + 1 < r.path.size(); ++i) {
    const int n = std::max(1, static_cast<int>(std::ceil((r.path[i + 1] - r.path[i]).norm() / kReplayStep_rad)));
    for (int k = 0; k < n; ++k) qs.push_back(r.path[i] + (r.path[i + 1] - r.path[i]) * (static_cast<double>(k) / n));
  }
  qs.push_back(r.path.back());
  double max_torque = 0.0;
  double max_force = 0.0;
  Eigen::VectorXd tau(model.numJoints());
  for (std::size_t k = 0; k < qs.size(); ++k) {
    const accessibility::PostureCheck c = checker.check(qs[k]);
    const arm::ArmData& fk = checker.lastKinematics();
    const haptics::ContactData& contact = checker.lastContact();
    const std::vector<haptics::LocalMinimum>& minima = checker.lastMinima();
    reports::ReplayFrame frame;
    frame.t_s = static_cast<double>(k) / 25.0;
    for (int l : links) {
      const arm::LinkGeometry& g = model.joints[static_cast<std::size_t>(l)].geometry;
      const Eigen::Vector3d a = arm::pointInWorld(fk, l, g.from_m);
      const Eigen::Vector3d b = arm::pointInWorld(fk, l, g.to_m);
      frame.segments_m.push_back({a.x(), a.y(), a.z(), b.x(), b.y(), b.z()});
      frame.penetrating.push_back(c.link_distance_m[static_cast<std::size_t>(l)] < p.params.force_threshold_m);
    }
    tau.setZero();
    for (std::size_t i = 0; i < minima.size(); ++i) {
      const haptics::LocalMinimum& m = minima[i];
      const double force = contact.rendered[i] != 0 ? contact.f_W[i].norm() : 0.0;
      max_force = std::max(max_force, force);
      if (contact.rendered[i] != 0)
        haptics::addTailoredJacobianTorques(model, fk, m.link, contact.p_W[i], contact.f_W[i], tau);
      frame.minima.push_back(
          {toArray(arm::pointInWorld(fk, m.link, m.p_L)), toArray(p.world->object(m.object).X_WO * m.p_O), force});
    }
    for (int j = 0; j < model.numArmJoints(); ++j) {
      frame.torques_nm.push_back(tau[j]);
      max_torque = std::max(max_torque, std::abs(tau[j]));
    }
    replay.frames.push_back(std::move(frame));
  }
  replay.torque_scale_nm = max_torque > 1e-6 ? max_torque : 1.0;
  replay.force_scale_n = max_force > 1e-6 ? max_force : 1.0;
  return replay;
}

// The push of one program in words: "412.3 N", "unbounded" (no torque limit binds), or why there
// is none.
std::string pushText(const accessibility::ForceLpResult& r) {
  if (r.status == accessibility::ForceStatus::kOptimal) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(1) << r.push_n << " N";
    return s.str();
  }
  return accessibility::toString(r.status);
}

// The joints whose torque limit binds the push, e.g. "R_SFE max, R_EB min".
std::string limitingText(const arm::ArmModel& model, const accessibility::HumanArm& human,
                         const accessibility::ForceLpResult& r) {
  const std::vector<int> joints = human.jointIndices();
  std::string text;
  for (const accessibility::ActiveLimit& a : r.active) {
    if (a.joint < 0 || a.joint >= static_cast<int>(joints.size())) continue;
    text += (text.empty() ? "" : ", ") +
            model.joints[static_cast<std::size_t>(joints[static_cast<std::size_t>(a.joint)])].name +
            (a.upper ? " max" : " min");
  }
  return text.empty() ? "none" : text;
}

nlohmann::json programJson(const arm::ArmModel& model, const accessibility::HumanArm& human,
                           const accessibility::ForceLpResult& r) {
  nlohmann::json j;
  j["status"] = accessibility::toString(r.status);
  j["push_n"] = r.status == accessibility::ForceStatus::kOptimal ? nlohmann::json(r.push_n) : nlohmann::json(nullptr);
  j["limiting"] = limitingText(model, human, r);
  return j;
}

nlohmann::json pushJson(const arm::ArmModel& model, const accessibility::HumanArm& human,
                        const accessibility::PushAnalysis& a) {
  nlohmann::json j;
  j["braced"] = programJson(model, human, a.braced);
  j["unbraced"] = programJson(model, human, a.unbraced);
  j["contacts"] = a.contacts.size();
  j["leverage"] = std::isfinite(a.leverage) ? nlohmann::json(a.leverage) : nlohmann::json(nullptr);
  j["leverage_unbounded"] = std::isinf(a.leverage);
  return j;
}

// Whether the best push meets the required force: an optimal push at least `force_n`, or a push
// no torque limit bounds.
bool strongEnough(const accessibility::ForceLpResult& best, double force_n) {
  if (best.status == accessibility::ForceStatus::kUnbounded) return true;
  return best.status == accessibility::ForceStatus::kOptimal && best.push_n >= force_n;
}

int exitCode(Verdict v) {
  return v == Verdict::kReachable ? kExitPass : v == Verdict::kUnreachable ? kExitFail : kExitInconclusive;
}

}  // namespace

CLI::App* addAccessCommand(CLI::App& app, AccessOptions& o, AccessMergeOptions& m, CLI::App*& merge,
                           OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "access", "Can the arm reach the scene's target: free, with contact allowed, hand only (OMPL, seeded)");
  OptionDeclarer declare(*cmd, table);
  declare.file("--scene", o.scene, "Scene YAML with targets (scenes/accessibility/env1.yaml); required");
  declare.name("--target", o.target, "Target name (default: the scene's first)");
  declare.file("--arm", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.folder("--out", o.out_dir, "Write summary.json and report.html to this folder");
  declare.integer("--seed", o.seed, "Seed of the planner's sampler (same seed, same verdict and path)", 0,
                  4294967295LL);
  declare.integer("--iterations", o.iterations, "Planner iterations per mode (the budget)", 1, 100000000LL);
  declare.choice("--planner", o.planner, "rrt-connect (OMPL RRT-Connect) or sbl (OMPL SBL, wrist projection)",
                 {"rrt-connect", "sbl"});
  declare.number("--max-link-force", o.max_link_force_n, "Contact allowed: largest rendered force per link [N]",
                 {0.0, 1e6, "N"});
  declare.number("--max-skin-depth", o.max_skin_depth_m,
                 "Contact allowed: largest depth into the haptic skin (below d_f) [m]", {0.0, 1.0, "m"});
  declare.number("--clearance", o.clearance_m, "Free and hand-only reach: clearance margin [m]", {0.0, 1.0, "m"});
  declare.number("--force", o.force_n,
                 "The push the task needs along the target's push direction [N]: exit 1 when the best push is smaller",
                 {0.0, 1e6, "N"});
  declare.file("--human", o.human_config,
               "The person's arm: strength and weight YAML (default: config/human_arm.yaml)");
  declare.integer("--brace-evaluations", o.brace_evaluations, "Budget of the brace-posture search (postures evaluated)",
                  1, 100000);
  declare.integer("--population", o.population,
                  "Run a population of this many technicians (with --force) instead of the nominal arm", 1,
                  100000000LL);
  declare.number("--mix", o.mix, "Population: the share of women", {0.0, 1.0, ""});
  declare.integer("--threads", o.threads, "Population: worker threads (0: one per core; under mpirun 0 means 1)", 0,
                  1024);
  declare.name("--shard", o.shard, "Population: run shard i of N (i/N, 1 <= i <= N); merge with `access merge`");
  declare.integer("--repair-iterations", o.repair_iterations,
                  "Population: planner iterations for each re-planned stretch of a repaired path", 1, 100000000LL);

  merge = cmd->add_subcommand("merge", "Merge the shards of a population (`access --population N --shard i/N`)");
  OptionDeclarer merge_declare(*merge, table);
  merge_declare.folder("--out", m.out_dir, "Write the merged summary.json, technicians.csv and report.html here")
      ->required();
  merge_declare.files("shards", m.shards, "The shards' technicians.sweep files (population.json beside each)")
      ->required();
  return cmd;
}

accessibility::ReachOptions accessReachOptions(const AccessOptions& o) {
  accessibility::ReachOptions ro;
  ro.seed = static_cast<std::uint32_t>(o.seed);
  ro.max_iterations = static_cast<long>(o.iterations);
  ro.planner = o.planner == "sbl" ? accessibility::ReachPlanner::kSbl : accessibility::ReachPlanner::kRrtConnect;
  ro.limits.max_link_force_n = o.max_link_force_n;
  ro.limits.max_skin_depth_m = o.max_skin_depth_m;
  ro.limits.clearance_margin_m = o.clearance_m;
  return ro;
}

accessibility::BraceSearchOptions accessBraceOptions(const AccessOptions& o) {
  accessibility::BraceSearchOptions bo;
  bo.max_evaluations = static_cast<int>(o.brace_evaluations);
  bo.seed = static_cast<std::uint64_t>(o.seed);
  bo.contact_force_max_n = o.max_link_force_n;
  bo.penetration_max_m = o.max_skin_depth_m;
  return bo;
}

int runAccess(const AccessOptions& o) {
  if (o.scene.empty()) throw core::ConfigError("", "--scene", "access needs a scene (--scene FILE)");
  if (o.population) throw core::ConfigError("", "--population", "a population runs with runAccessPopulation");
  if (!o.shard.empty()) throw core::ConfigError("", "--shard", "--shard needs --population");
  const arm::ArmModel model = arm::loadArmModel(configPathOr(o.arm_config, arm::defaultArmModelPath));
  std::cerr << "access: loading scene " << o.scene << "\n";
  const haptics::Scene scene = haptics::loadScene(o.scene);
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, model);
  accessibility::ReachProblem p;
  p.model = &model;
  p.world = &world;
  p.params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  p.target = accessibility::resolveTarget(scene, model, o.target);
  if (scene.posture("rest") == nullptr) {
    throw core::ConfigError(scene.source, "arm.postures", "the scene has no posture 'rest' (the start of the reach)");
  }
  p.q_start = haptics::scenePosture(scene, "rest", model);
  const accessibility::HumanArm human =
      accessibility::loadHumanArm(configPathOr(o.human_config, accessibility::defaultHumanArmPath), model);
  const accessibility::ReachOptions ro = accessReachOptions(o);
  std::cerr << "access: target '" << p.target.name << "' on '" << p.target.object << "'; goal sweep and " << o.planner
            << " in three modes (" << o.iterations << " iterations each, seed " << o.seed << ")\n";
  const accessibility::ReachStudy study = accessibility::studyReach(p, ro);

  // The push at the reached grasp (the contact-allowed path's end) and the brace posture.
  std::optional<accessibility::BraceSearchResult> brace;
  if (study.contact.verdict == Verdict::kReachable) {
    std::cerr << "access: push along the target's push direction, brace-posture search (" << o.brace_evaluations
              << " postures, seed " << o.seed << ")\n";
    const std::unique_ptr<haptics::GlobalSearch> search = haptics::makeGlobalSearch(haptics::SearchKind::kSnch, world);
    const accessibility::BraceSearchOptions bo = accessBraceOptions(o);
    brace = accessibility::searchBracePosture(model, human, world, *search, p.params, study.contact.path.back(),
                                              p.target.push_W, bo);
  }
  const bool strong = !brace || !o.force_n || strongEnough(brace->best.braced, *o.force_n);

  std::cout << "Scene " << scene.name << ", target " << p.target.name << "\n";
  for (const ReachResult* r : {&study.free, &study.contact, &study.hand_only}) {
    std::cout << "  " << accessibility::reachModeName(r->mode) << ": " << accessibility::verdictName(r->verdict) << " ("
              << r->reason << ")\n";
  }
  if (study.handOnlyFalsePositive()) {
    std::cout << "  FALSE POSITIVE of hand-only reach: the hand reaches, the arm cannot be there\n";
  }
  if (study.contact.verdict == Verdict::kReachable) {
    std::cout << "  contact-allowed path, per link: smallest distance [mm], largest force [N]\n";
    for (std::size_t l = 0; l < study.contact.links.size(); ++l) {
      std::cout << "    " << model.joints[static_cast<std::size_t>(study.contact.links[l])].name << ": ";
      if (std::isfinite(study.contact.path_min_distance_m[l])) {
        std::cout << study.contact.path_min_distance_m[l] * 1e3;
      } else {
        std::cout << "beyond the search cutoff";
      }
      std::cout << ", " << study.contact.path_max_force_n[l] << "\n";
    }
  }

  if (brace) {
    std::cout << "  push along the target's push direction (" << human.source.filename().string() << "):\n"
              << "    at the reached grasp: " << pushText(brace->start.braced) << " braced ("
              << brace->start.contacts.size() << " contacts), " << pushText(brace->start.unbraced) << " unbraced\n"
              << "    at the brace posture (" << brace->evaluations
              << " postures searched): " << pushText(brace->best.braced) << " braced (" << brace->best.contacts.size()
              << " contacts), " << pushText(brace->best.unbraced) << " unbraced; limited by "
              << limitingText(model, human, brace->best.braced) << "\n";
    if (o.force_n) {
      std::cout << "    the task needs " << *o.force_n << " N: " << (strong ? "strong enough" : "TOO WEAK") << "\n";
    }
  }

  if (!o.out_dir.empty()) {
    const bool reachable = study.contact.verdict == Verdict::kReachable;
    reports::Report report("access", "Accessibility: " + scene.name + ", target " + p.target.name);
    report.setVerdict(reachable && strong,
                      std::string("Contact-allowed reach: ") + accessibility::verdictName(study.contact.verdict) +
                          (study.handOnlyFalsePositive() ? " (hand-only reach is a false positive)" : "") +
                          (reachable && !strong ? "; the person is too weak for the task's push" : ""));
    nlohmann::json& r = report.results()["access"];
    r["scene"] = scene.name;
    r["scene_file"] = std::filesystem::absolute(scene.source).string();
    r["target"] = p.target.name;
    r["seed"] = o.seed;
    r["iterations_budget"] = o.iterations;
    r["limits"] = {{"clearance_margin_m", ro.limits.clearance_margin_m},
                   {"max_link_force_n", ro.limits.max_link_force_n},
                   {"max_skin_depth_m", ro.limits.max_skin_depth_m},
                   {"force_threshold_m", p.params.force_threshold_m}};
    r["free"] = resultJson(model, study.free);
    r["contact_allowed"] = resultJson(model, study.contact);
    r["hand_only"] = resultJson(model, study.hand_only);
    r["hand_only_false_positive"] = study.handOnlyFalsePositive();
    if (brace) {
      nlohmann::json& f = r["force"];
      f["human_file"] = std::filesystem::absolute(human.source).string();
      f["push_direction_W"] = {p.target.push_W.x(), p.target.push_W.y(), p.target.push_W.z()};
      f["required_push_n"] = o.force_n ? nlohmann::json(*o.force_n) : nlohmann::json(nullptr);
      f["strong_enough"] = strong;
      f["at_grasp"] = pushJson(model, human, brace->start);
      f["at_grasp"]["q_rad"] = std::vector<double>(brace->q_start_rad.data(), brace->q_start_rad.data() + 7);
      f["brace_posture"] = pushJson(model, human, brace->best);
      f["brace_posture"]["q_rad"] = std::vector<double>(brace->q_best_rad.data(), brace->q_best_rad.data() + 7);
      f["evaluations"] = brace->evaluations;
      f["rejected_contact"] = brace->rejected_contact;
      f["rejected_limits"] = brace->rejected_limits;
    }

    reports::Table verdicts;
    verdicts.caption = "Reach in three modes";
    verdicts.columns = {"Mode", "Verdict", "Valid goals", "Solved goals", "Iterations", "Reason"};
    for (const ReachResult* x : {&study.free, &study.contact, &study.hand_only}) {
      verdicts.rows.push_back({accessibility::reachModeName(x->mode), accessibility::verdictName(x->verdict),
                               static_cast<double>(x->goals.valid), static_cast<double>(x->goals.solved),
                               static_cast<double>(x->iterations), x->reason});
    }
    reports::Section& section = report.addSection("Verdicts");
    section.addTable(std::move(verdicts));
    for (const ReachResult* x : {&study.free, &study.contact, &study.hand_only}) {
      if (x->verdict != Verdict::kReachable) continue;
      reports::Table links;
      links.caption = std::string("Along the ") + accessibility::reachModeName(x->mode) +
                      " path: each link's smallest distance (-1: beyond the search cutoff) and largest force";
      links.columns = {"Link", "Smallest distance [mm]", "Largest force [N]"};
      for (std::size_t l = 0; l < x->links.size(); ++l) {
        links.rows.push_back({model.joints[static_cast<std::size_t>(x->links[l])].name,
                              finiteOrNegative(x->path_min_distance_m[l]), x->path_max_force_n[l]});
      }
      section.addTable(std::move(links));
    }
    if (brace) {
      reports::Table push;
      push.caption = "Push along the target's push direction (the person's arm: " + human.source.filename().string() +
                     "); the brace posture is the best of " + std::to_string(brace->evaluations) +
                     " postures along the self-motion";
      push.columns = {"Posture", "Braced", "Unbraced", "Contacts", "Limited by (braced)"};
      push.rows.push_back({"reached grasp", pushText(brace->start.braced), pushText(brace->start.unbraced),
                           static_cast<double>(brace->start.contacts.size()),
                           limitingText(model, human, brace->start.braced)});
      push.rows.push_back({"brace posture", pushText(brace->best.braced), pushText(brace->best.unbraced),
                           static_cast<double>(brace->best.contacts.size()),
                           limitingText(model, human, brace->best.braced)});
      report.addSection("Force with bracing").addTable(std::move(push));
    }
    // The path in 3D: contact-allowed reach's, else hand-only reach's (the false positive shown).
    const ReachResult* shown = study.contact.verdict == Verdict::kReachable     ? &study.contact
                               : study.hand_only.verdict == Verdict::kReachable ? &study.hand_only
                                                                                : nullptr;
    if (shown != nullptr) {
      std::cerr << "access: posing the " << accessibility::reachModeName(shown->mode) << " path for the report\n";
      report.addSection("Path in 3D").addReplay3d(pathReplay(p, scene, ro.limits, *shown));
    }
    writeReport(report, o.out_dir);
    std::cout << "\nReport: " << (std::filesystem::absolute(o.out_dir) / "report.html").string() << "\n";
  }
  if (!strong) return kExitFail;
  return exitCode(study.contact.verdict);
}

AccessDemoStep runAccessDemoStep(const arm::ArmModel& model, reports::Report& report) {
  const haptics::HapticsParams params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  reports::Table table;
  table.caption = "Valve study: the five environments in three reach modes";
  table.columns = {"Environment", "Free", "Contact allowed", "Hand only", "Hand-only false positive", "As designed"};
  AccessDemoStep step;
  step.pass = true;
  int false_positives = 0;
  for (int env = 1; env <= 5; ++env) {
    const haptics::Scene scene =
        haptics::loadScene(core::defaultScenePath("accessibility/env" + std::to_string(env) + ".yaml"));
    const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, model);
    accessibility::ReachProblem p;
    p.model = &model;
    p.world = &world;
    p.params = params;
    p.target = accessibility::resolveTarget(scene, model, "");
    p.q_start = haptics::scenePosture(scene, "rest", model);
    const accessibility::ReachStudy s = accessibility::studyReach(p, accessibility::ReachOptions{});
    const bool free_ok = (env == 3) == (s.free.verdict == Verdict::kReachable);
    const bool contact_ok =
        (env == 2) ? s.contact.verdict == Verdict::kUnreachable : s.contact.verdict == Verdict::kReachable;
    const bool designed = free_ok && contact_ok && (env != 2 || s.handOnlyFalsePositive());
    step.pass = step.pass && designed;
    false_positives += s.handOnlyFalsePositive() ? 1 : 0;
    table.rows.push_back({scene.name, accessibility::verdictName(s.free.verdict),
                          accessibility::verdictName(s.contact.verdict),
                          accessibility::verdictName(s.hand_only.verdict), s.handOnlyFalsePositive() ? "yes" : "no",
                          designed ? "yes" : "no"});
  }
  std::ostringstream detail;
  detail << (step.pass ? "every environment gives its designed verdicts" : "an environment missed its verdicts")
         << "; hand-only false positives: " << false_positives;
  step.detail = detail.str();
  report.addSection("Valve study, full-arm vs hand-only").addTable(std::move(table));
  report.results()["access_demo"] = {{"pass", step.pass}, {"hand_only_false_positives", false_positives}};
  return step;
}

}  // namespace fullarm::app
