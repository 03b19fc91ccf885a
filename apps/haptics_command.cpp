#include "haptics_command.hpp"

#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>
#include <utility>
#include <vector>

#include "cli_values.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/query.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/reports/report.hpp"
#include "output_files.hpp"
#include "result_tables.hpp"

namespace fullarm::app {
namespace {

constexpr const char* kDemoScene = "valve_wall.yaml";
constexpr const char* kDemoPosture = "reach_valve";

nlohmann::json listJson(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

const char* featureName(haptics::FeatureKind k) {
  return k == haptics::FeatureKind::kFace ? "face" : (k == haptics::FeatureKind::kEdge ? "edge" : "vertex");
}

const std::string& linkName(const arm::ArmModel& model, int link) {
  return model.joints[static_cast<std::size_t>(link)].name;
}

bool torquesFinite(const haptics::QueryResult& query, const haptics::QueryRendering& x) {
  return x.tau_contact_nm.allFinite() && query.tau_gravity_nm.allFinite() && x.tau_total_nm.allFinite();
}

std::string linksInContactText(const arm::ArmModel& model, const haptics::ContactData& contact) {
  std::ostringstream out;
  out << std::fixed;
  bool any = false;
  for (int l = 0; l < model.numJoints(); ++l) {
    const haptics::LinkContactRecord& r = contact.links[static_cast<std::size_t>(l)];
    if (!r.in_contact && !r.penetrating) continue;
    out << (any ? ", " : "") << linkName(model, l) << " (depth " << std::setprecision(1) << r.depth_m * 1e3 << " mm"
        << (r.penetrating ? ", penetrating" : "") << ")";
    any = true;
  }
  return any ? out.str() : "none";
}

}  // namespace

CLI::App* addHapticsCommand(CLI::App& app, HapticsQueryOptions& o, OptionTable& table) {
  CLI::App* haptics = app.add_subcommand("haptics", "Full-arm haptic rendering: minima, contact forces, torques");
  haptics->require_subcommand(1);
  CLI::App* query = haptics->add_subcommand(
      "query", "Global search of the arm against a scene at one configuration; print the minima, forces and torques");
  OptionDeclarer declare(*query, table);
  declare.file("--scene", o.scene, "Scene YAML (scenes/valve_wall.yaml)")->required();
  declare.numberList("--q", o.q_text, "Joint angles [rad], e.g. \"1.2,-0.3,0,0.7,0,0,0\"")->required();
  declare.folder("--out", o.out_dir, "Write summary.json and report.html to this folder");
  declare.choice("--mode", o.mode, "full-arm: every link renders; hand-only: only the hand (the paper's baseline)",
                 {"full-arm", "hand-only"});
  declare.choice("--search", o.search, "Global search: snch (spatialized normal cones) or bullet (Bullet 3)",
                 {"snch", "bullet"});
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--haptics-config", o.haptics_config, "Haptics YAML (default: config/haptics.yaml)");
  return query;
}

int runHapticsQuery(const HapticsQueryOptions& o) {
  const arm::ArmModel model = arm::loadArmModel(configPathOr(o.arm_config, arm::defaultArmModelPath));
  haptics::HapticsParams params =
      haptics::loadHapticsParams(configPathOr(o.haptics_config, haptics::defaultHapticsParamsPath));
  params.mode = o.mode == "hand-only" ? haptics::RenderMode::kHandOnly : haptics::RenderMode::kFullArm;
  const Eigen::VectorXd q = parseJointVector(o.q_text, model, "--q");
  const haptics::Scene scene = haptics::loadScene(o.scene);
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, model);
  const std::unique_ptr<haptics::GlobalSearch> search = haptics::makeGlobalSearch(
      o.search == "bullet" ? haptics::SearchKind::kBullet : haptics::SearchKind::kSnch, world);
  const haptics::RenderMode modes[] = {params.mode};
  const haptics::QueryResult query = haptics::renderQuery(model, world, *search, params, q, modes);
  const std::vector<haptics::LocalMinimum>& minima = query.minima;
  const haptics::QueryRendering& rendering = query.renderings.front();
  const haptics::ContactData& contact = rendering.contact;
  const double search_ms = query.search_ms;
  const Eigen::Isometry3d X_SW = haptics::armBasePose(scene, model);

  // Console output.
  std::cout << "Scene " << scene.name << " (" << scene.objects.size() << " objects, " << scene.numTriangles()
            << " triangles), search " << search->name() << ", mode " << o.mode << "\n";
  std::cout << "cutoff L = " << params.cutoff_m * 1e3 << " mm, force threshold d_f = " << params.force_threshold_m * 1e3
            << " mm, pruning radius r = " << params.prune_radius_m * 1e3 << " mm; global search " << std::fixed
            << std::setprecision(2) << search_ms << " ms\n\n";
  std::cout << minima.size() << " minima within L (points in the scene frame):\n";
  std::cout << "  link      object                      d [mm]   feature link/object   point on link [m]          "
               "force [N]\n";
  for (std::size_t i = 0; i < minima.size(); ++i) {
    const haptics::LocalMinimum& m = minima[i];
    const Eigen::Vector3d p_S = X_SW * query.X_WL[static_cast<std::size_t>(m.link)] * m.p_L;
    const auto kind = featureName;
    std::cout << "  " << std::left << std::setw(9) << model.joints[static_cast<std::size_t>(m.link)].name << " "
              << std::setw(26) << scene.objects[static_cast<std::size_t>(m.object)].name << std::right << std::setw(8)
              << std::setprecision(3) << m.distance_m * 1e3 << "   " << std::left << std::setw(6)
              << kind(m.feature_link.kind) << "/" << std::setw(13) << kind(m.feature_object.kind) << std::right
              << std::setprecision(3) << " (" << p_S.x() << ", " << p_S.y() << ", " << p_S.z() << ")   "
              << std::setprecision(2) << contact.f_W[i].norm() << (contact.rendered[i] ? "" : " (not rendered)")
              << "\n";
  }
  std::cout << "\nJoint torques [N m]:\n  joint     contact   gravity     total\n";
  for (int j = 0; j < model.numJoints(); ++j) {
    std::cout << "  " << std::left << std::setw(7) << model.joints[static_cast<std::size_t>(j)].name << std::right
              << std::setw(10) << std::setprecision(3) << rendering.tau_contact_nm[j] << std::setw(10)
              << query.tau_gravity_nm[j] << std::setw(10) << rendering.tau_total_nm[j] << "\n";
  }
  std::cout << "\nLinks in contact (d < d_f): " << linksInContactText(model, contact) << "\n";
  if (!contact.status.ok())
    std::cout << "FAULT: the contact computation rejected its input; contact torques are zero\n";

  if (!o.out_dir.empty()) {
    reports::Report report("haptics query", "Haptic query: " + scene.name);
    report.setVerdict(contact.status.ok(), !contact.status.ok()
                                               ? "The contact computation flagged a fault"
                                               : std::to_string(minima.size()) + " minima, " +
                                                     std::to_string(contact.active_springs) + " active springs");
    report.addHeadlineNumber("minima", "Minima within L", static_cast<double>(minima.size()), "");
    report.addHeadlineNumber("active_springs", "Active springs", contact.active_springs, "");
    report.addHeadlineNumber("search_ms", "Global search", search_ms, "ms");
    nlohmann::json& r = report.results()["haptics"];
    r["scene"] = scene.name;
    r["scene_file"] = std::filesystem::absolute(scene.source).string();
    r["search"] = query.search;
    r["mode"] = o.mode;
    r["q_rad"] = std::vector<double>(q.data(), q.data() + q.size());
    r["cutoff_m"] = params.cutoff_m;
    r["force_threshold_m"] = params.force_threshold_m;
    r["prune_radius_m"] = params.prune_radius_m;
    r["search_ms"] = search_ms;
    r["fault"] = !contact.status.ok();
    ResultTable minima_table = minimaTable(model, scene, world, query, "Minima within the cutoff (scene frame)");
    ResultTable torques = jointTorquesTable(model, query, "Joint torques");
    ResultTable links = linkRecordsTable(model, scene, query, "Per-link contact records");
    reports::Section& section = report.addSection("Minima, forces and torques");
    for (ResultTable* t : {&minima_table, &torques, &links}) {
      mergeJson(r, t->json);
      section.addTable(std::move(t->table));
    }
    writeReport(report, o.out_dir);
    std::cout << "\nReport: " << (std::filesystem::absolute(o.out_dir) / "report.html").string() << "\n";
  }
  return contact.status.ok() ? 0 : 1;
}

HapticsDemoStep runHapticsDemoStep(const arm::ArmModel& model, const std::filesystem::path& /*out_dir*/,
                                   reports::Report& report) {
  const haptics::Scene scene = haptics::loadScene(core::defaultScenePath(kDemoScene));
  const haptics::HapticsParams params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  const Eigen::VectorXd q = haptics::scenePosture(scene, kDemoPosture, model);
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, model);
  // The global search does not depend on the rendering mode (it finds the minima of every link);
  // the mode decides which minima make forces. One search, two renderings.
  haptics::SnchGlobalSearch search;
  const haptics::RenderMode modes[] = {haptics::RenderMode::kFullArm, haptics::RenderMode::kHandOnly};
  const haptics::QueryResult query = haptics::renderQuery(model, world, search, params, q, modes);
  const std::vector<haptics::LocalMinimum>& minima = query.minima;
  const haptics::QueryRendering& full = query.renderings[0];
  const haptics::QueryRendering& hand = query.renderings[1];
  const double search_ms = query.search_ms;
  const int n = model.numJoints();

  const bool no_fault = full.contact.status.ok() && hand.contact.status.ok();
  const bool found = !minima.empty();
  const bool finite = torquesFinite(query, full) && torquesFinite(query, hand);
  HapticsDemoStep step;
  step.pass = no_fault && found && finite;
  std::ostringstream detail;
  detail << minima.size() << " minima at " << kDemoPosture << " in " << scene.name << "; active springs full-arm "
         << full.contact.active_springs << ", hand-only " << hand.contact.active_springs << "; |tau_contact| "
         << std::fixed << std::setprecision(2) << full.tau_contact_nm.norm() << " vs " << hand.tau_contact_nm.norm()
         << " N m";
  if (!no_fault) detail << "; CONTACT FAULT";
  if (!found) detail << "; no minimum within the cutoff";
  if (!finite) detail << "; non-finite joint torque";
  step.detail = detail.str();

  // Console (the demo's later output keeps its own number format).
  const std::ios_base::fmtflags cout_flags = std::cout.flags();
  const std::streamsize cout_precision = std::cout.precision();
  std::cout << "  scene " << scene.name << " (" << scene.objects.size() << " objects, " << scene.numTriangles()
            << " triangles), posture " << kDemoPosture << ", SNCH search " << std::fixed << std::setprecision(2)
            << search_ms << " ms, " << minima.size() << " minima within L = " << params.cutoff_m * 1e3 << " mm\n";
  std::cout << "  joint     contact full-arm  contact hand-only   gravity  total full-arm  total hand-only [N m]\n";
  for (int j = 0; j < n; ++j) {
    std::cout << "  " << std::left << std::setw(7) << linkName(model, j) << std::right << std::setprecision(3)
              << std::setw(18) << full.tau_contact_nm[j] << std::setw(19) << hand.tau_contact_nm[j] << std::setw(10)
              << query.tau_gravity_nm[j] << std::setw(16) << full.tau_total_nm[j] << std::setw(17)
              << hand.tau_total_nm[j] << "\n";
  }
  std::cout << "  links in contact (d < d_f): " << linksInContactText(model, full.contact) << "\n";
  std::cout.flags(cout_flags);
  std::cout.precision(cout_precision);

  // summary.json: results.haptics_demo.
  nlohmann::json& r = report.results()["haptics_demo"];
  r["pass"] = step.pass;
  r["scene"] = scene.name;
  r["scene_file"] = std::filesystem::absolute(scene.source).string();
  r["posture"] = kDemoPosture;
  r["q_rad"] = listJson(q);
  r["search"] = query.search;
  r["search_ms"] = search_ms;
  r["cutoff_m"] = params.cutoff_m;
  r["force_threshold_m"] = params.force_threshold_m;
  r["prune_radius_m"] = params.prune_radius_m;
  r["num_minima"] = minima.size();
  ResultTable minima_table = minimaTable(model, scene, world, query,
                                         "Minima within the cutoff at " + std::string(kDemoPosture) +
                                             " (one SNCH search; the mode decides which minima make forces)");
  for (const haptics::QueryRendering& x : query.renderings) {
    nlohmann::json& mode = r[modeKey(x.mode)];
    mode["fault"] = !x.contact.status.ok();
    mode["active_springs"] = x.contact.active_springs;
  }
  ResultTable torques =
      jointTorquesTable(model, query, "Joint torques at " + std::string(kDemoPosture) + ", full-arm vs hand-only");
  std::ostringstream df_text;
  df_text << std::fixed << std::setprecision(1) << params.force_threshold_m * 1e3;
  ResultTable links = linkRecordsTable(
      model, scene, query, "Per-link contact records (recorded in both modes; d_f = " + df_text.str() + " mm)");
  for (const ResultTable* t : {&minima_table, &torques, &links}) mergeJson(r, t->json);
  report.addHeadlineNumber("haptics_minima", "Minima at the valve reach", static_cast<double>(minima.size()), "");
  report.addHeadlineNumber("haptics_tau_contact_full_arm_nm", "Contact torque norm, full-arm",
                           full.tau_contact_nm.norm(), "N·m");
  reports::Section& section = report.addSection("Haptic rendering at the valve opening");
  section.addParagraph("The arm at the scene's " + std::string(kDemoPosture) + " posture in " + scene.name + " (" +
                       scene.description + "). " + step.detail +
                       ". Full-arm mode renders a spring at every minimum "
                       "closer than d_f; hand-only mode (the paper's baseline) only at minima on the hand links, "
                       "while the contact records still cover every link.");
  for (ResultTable* t : {&minima_table, &torques, &links}) section.addTable(std::move(t->table));
  return step;
}

}  // namespace fullarm::app
