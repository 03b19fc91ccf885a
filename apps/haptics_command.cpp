#include "haptics_command.hpp"

#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "cli_values.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/bullet_search.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/reports/report.hpp"

namespace fullarm::app {
namespace {

constexpr double kTickPeriod_s = 1e-3;  // durations of the contact records: one haptic tick

nlohmann::json vectorJson(const Eigen::Vector3d& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

}  // namespace

CLI::App* addHapticsCommand(CLI::App& app, HapticsQueryOptions& o) {
  CLI::App* haptics = app.add_subcommand("haptics", "Full-arm haptic rendering: minima, contact forces, torques");
  haptics->require_subcommand(1);
  CLI::App* query = haptics->add_subcommand(
      "query", "Global search of the arm against a scene at one configuration; print the minima, forces and torques");
  query->add_option("--scene", o.scene, "Scene YAML (scenes/valve_wall.yaml)")->required()->check(CLI::ExistingFile);
  query->add_option("--q", o.q_text, "Joint angles [rad], e.g. \"1.2,-0.3,0,0.7,0,0,0\"")->required();
  query->add_option("--out", o.out_dir, "Write summary.json and report.html to this folder");
  query->add_option("--mode", o.mode, "full-arm: every link renders; hand-only: only the hand (the paper's baseline)")
      ->check(CLI::IsMember({"full-arm", "hand-only"}))
      ->capture_default_str();
  query->add_option("--search", o.search, "Global search: snch (spatialized normal cones) or bullet (Bullet 3)")
      ->check(CLI::IsMember({"snch", "bullet"}))
      ->capture_default_str();
  query->add_option("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)")
      ->check(CLI::ExistingFile);
  query->add_option("--haptics-config", o.haptics_config, "Haptics YAML (default: config/haptics.yaml)")
      ->check(CLI::ExistingFile);
  return query;
}

int runHapticsQuery(const HapticsQueryOptions& o) {
  const arm::ArmModel model =
      arm::loadArmModel(o.arm_config.empty() ? arm::defaultArmModelPath() : std::filesystem::path(o.arm_config));
  haptics::HapticsParams params = haptics::loadHapticsParams(
      o.haptics_config.empty() ? haptics::defaultHapticsParamsPath() : std::filesystem::path(o.haptics_config));
  params.mode = o.mode == "hand-only" ? haptics::RenderMode::kHandOnly : haptics::RenderMode::kFullArm;
  const Eigen::VectorXd q = parseJointVector(o.q_text, model, "--q");
  const haptics::Scene scene = haptics::loadScene(o.scene);
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, model);
  std::unique_ptr<haptics::GlobalSearch> search;
  if (o.search == "bullet") {
    search = std::make_unique<haptics::BulletGlobalSearch>(world);
  } else {
    search = std::make_unique<haptics::SnchGlobalSearch>();
  }

  arm::ArmData fk(model);
  arm::computeForwardKinematics(model, fk, q);
  std::vector<haptics::LocalMinimum> minima;
  const auto start = std::chrono::steady_clock::now();
  search->search(world, fk, params.cutoff_m, params.prune_radius_m, minima);
  const double search_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  haptics::ContactData contact(model, std::max<int>(1, static_cast<int>(minima.size())));
  haptics::computeContactForces(params, model, fk, minima, kTickPeriod_s, contact);
  haptics::computeContactTorques(model, fk, minima, contact);
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
    const Eigen::Vector3d p_S = X_SW * fk.X_WL[static_cast<std::size_t>(m.link)] * m.p_L;
    const auto kind = [](haptics::FeatureKind k) {
      return k == haptics::FeatureKind::kFace ? "face" : (k == haptics::FeatureKind::kEdge ? "edge" : "vertex");
    };
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
              << std::setw(10) << std::setprecision(3) << contact.tau_contact[j] << std::setw(10)
              << contact.tau_gravity[j] << std::setw(10) << contact.tau_total[j] << "\n";
  }
  std::cout << "\nLinks in contact (d < d_f):";
  bool any = false;
  for (int l = 0; l < model.numJoints(); ++l) {
    const haptics::LinkContactRecord& r = contact.links[static_cast<std::size_t>(l)];
    if (!r.in_contact && !r.penetrating) continue;
    any = true;
    std::cout << " " << model.joints[static_cast<std::size_t>(l)].name << " (depth " << std::setprecision(1)
              << r.depth_m * 1e3 << " mm" << (r.penetrating ? ", penetrating" : "") << ")";
  }
  std::cout << (any ? "\n" : " none\n");
  if (contact.fault) std::cout << "FAULT: the contact computation rejected its input; contact torques are zero\n";

  if (!o.out_dir.empty()) {
    reports::Report report("haptics query", "Haptic query: " + scene.name);
    report.setVerdict(!contact.fault, contact.fault ? "The contact computation flagged a fault"
                                                    : std::to_string(minima.size()) + " minima, " +
                                                          std::to_string(contact.active_springs) + " active springs");
    report.addHeadlineNumber("minima", "Minima within L", static_cast<double>(minima.size()), "");
    report.addHeadlineNumber("active_springs", "Active springs", contact.active_springs, "");
    report.addHeadlineNumber("search_ms", "Global search", search_ms, "ms");
    nlohmann::json& r = report.results()["haptics"];
    r["scene"] = scene.name;
    r["scene_file"] = std::filesystem::absolute(scene.source).string();
    r["search"] = std::string(search->name());
    r["mode"] = o.mode;
    r["q_rad"] = std::vector<double>(q.data(), q.data() + q.size());
    r["cutoff_m"] = params.cutoff_m;
    r["force_threshold_m"] = params.force_threshold_m;
    r["prune_radius_m"] = params.prune_radius_m;
    r["search_ms"] = search_ms;
    nlohmann::json list = nlohmann::json::array();
    reports::Table table;
    table.caption = "Minima within the cutoff (scene frame)";
    table.columns = {"Link", "Object", "Distance [mm]", "Force [N]", "Rendered", "x [m]", "y [m]", "z [m]"};
    for (std::size_t i = 0; i < minima.size(); ++i) {
      const haptics::LocalMinimum& m = minima[i];
      const Eigen::Vector3d p_S = X_SW * fk.X_WL[static_cast<std::size_t>(m.link)] * m.p_L;
      const Eigen::Vector3d q_S = X_SW * world.object(m.object).X_WO * m.p_O;
      list.push_back({{"link", model.joints[static_cast<std::size_t>(m.link)].name},
                      {"object", scene.objects[static_cast<std::size_t>(m.object)].name},
                      {"distance_m", m.distance_m},
                      {"point_link_scene_m", vectorJson(p_S)},
                      {"point_object_scene_m", vectorJson(q_S)},
                      {"force_n", vectorJson(X_SW.linear() * contact.f_W[i])},
                      {"rendered", contact.rendered[i] != 0}});
      table.rows.push_back({model.joints[static_cast<std::size_t>(m.link)].name,
                            scene.objects[static_cast<std::size_t>(m.object)].name, m.distance_m * 1e3,
                            contact.f_W[i].norm(), contact.rendered[i] ? "yes" : "no", p_S.x(), p_S.y(), p_S.z()});
    }
    r["minima"] = list;
    r["tau_contact_nm"] =
        std::vector<double>(contact.tau_contact.data(), contact.tau_contact.data() + model.numJoints());
    r["tau_gravity_nm"] =
        std::vector<double>(contact.tau_gravity.data(), contact.tau_gravity.data() + model.numJoints());
    r["tau_total_nm"] = std::vector<double>(contact.tau_total.data(), contact.tau_total.data() + model.numJoints());
    r["fault"] = contact.fault;
    reports::Table torques;
    torques.caption = "Joint torques";
    torques.columns = {"Joint", "Contact [N·m]", "Gravity [N·m]", "Total [N·m]"};
    for (int j = 0; j < model.numJoints(); ++j) {
      torques.rows.push_back({model.joints[static_cast<std::size_t>(j)].name, contact.tau_contact[j],
                              contact.tau_gravity[j], contact.tau_total[j]});
    }
    reports::Section& section = report.addSection("Minima, forces and torques");
    section.addTable(std::move(table));
    section.addTable(std::move(torques));
    report.write(o.out_dir);
    std::cout << "\nReport: " << (std::filesystem::absolute(o.out_dir) / "report.html").string() << "\n";
  }
  return contact.fault ? 1 : 0;
}

}  // namespace fullarm::app
