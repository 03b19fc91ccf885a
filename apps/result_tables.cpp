#include "result_tables.hpp"

#include <cmath>
#include <utility>
#include <vector>

namespace fullarm::app {
namespace {

nlohmann::json vectorJson(const Eigen::Vector3d& v) {
  return nlohmann::json::array({v.x(), v.y(), v.z()});
}

nlohmann::json listJson(const Eigen::VectorXd& v) {
  return std::vector<double>(v.data(), v.data() + v.size());
}

const std::string& linkName(const arm::ArmModel& model, int link) {
  return model.joints[static_cast<std::size_t>(link)].name;
}

// "<prefix> [unit]" with one rendering, "<prefix> <mode> [unit]" with several.
std::string column(const haptics::QueryResult& query, std::size_t index, const std::string& prefix,
                   const std::string& unit) {
  if (query.renderings.size() == 1) return prefix + " [" + unit + "]";
  return prefix + " " + modeLabel(query.renderings[index].mode) + " [" + unit + "]";
}

}  // namespace

void mergeJson(nlohmann::json& target, const nlohmann::json& part) {
  for (const auto& [key, value] : part.items()) {
    if (value.is_object() && target.contains(key) && target[key].is_object()) {
      mergeJson(target[key], value);
    } else {
      target[key] = value;
    }
  }
}

std::string modeKey(haptics::RenderMode mode) {
  return mode == haptics::RenderMode::kHandOnly ? "hand_only" : "full_arm";
}

std::string modeLabel(haptics::RenderMode mode) {
  return mode == haptics::RenderMode::kHandOnly ? "hand-only" : "full-arm";
}

nlohmann::json& renderingJson(nlohmann::json& json, const haptics::QueryResult& query, std::size_t index) {
  if (query.renderings.size() == 1) return json;
  return json[modeKey(query.renderings[index].mode)];
}

ResultTable minimaTable(const arm::ArmModel& model, const haptics::Scene& scene, const haptics::CollisionWorld& world,
                        const haptics::QueryResult& query, std::string caption) {
  const Eigen::Isometry3d X_SW = haptics::armBasePose(scene, model);
  const Eigen::Matrix3d R_SW = X_SW.linear();
  const bool side_by_side = query.renderings.size() > 1;
  ResultTable out;
  out.table.caption = std::move(caption);
  out.table.columns = {"Link"};
  if (side_by_side) out.table.columns.push_back("Hand link");
  out.table.columns.insert(out.table.columns.end(), {"Object", "Distance [mm]"});
  for (std::size_t k = 0; k < query.renderings.size(); ++k) out.table.columns.push_back(column(query, k, "Force", "N"));
  if (!side_by_side) out.table.columns.push_back("Rendered");
  out.table.columns.insert(out.table.columns.end(), {"x [m]", "y [m]", "z [m]"});

  nlohmann::json list = nlohmann::json::array();
  for (std::size_t i = 0; i < query.minima.size(); ++i) {
    const haptics::LocalMinimum& m = query.minima[i];
    const Eigen::Vector3d p_S = X_SW * query.X_WL[static_cast<std::size_t>(m.link)] * m.p_L;
    const bool hand_link = haptics::isHandLink(model, m.link);
    const std::string& object = scene.objects[static_cast<std::size_t>(m.object)].name;
    nlohmann::json entry = {{"link", linkName(model, m.link)},
                            {"object", object},
                            {"distance_m", m.distance_m},
                            {"point_link_scene_m", vectorJson(p_S)}};
    std::vector<reports::Cell> row = {linkName(model, m.link)};
    if (side_by_side) {
      entry["hand_link"] = hand_link;
      row.emplace_back(hand_link ? "yes" : "no");
    } else {
      entry["point_object_scene_m"] = vectorJson(X_SW * world.object(m.object).X_WO * m.p_O);
    }
    row.insert(row.end(), {object, m.distance_m * 1e3});
    for (std::size_t k = 0; k < query.renderings.size(); ++k) {
      const haptics::ContactData& contact = query.renderings[k].contact;
      const std::string suffix = side_by_side ? "_" + modeKey(query.renderings[k].mode) : "";
      entry["force" + suffix + "_n"] = vectorJson(Eigen::Vector3d(R_SW * contact.f_W[i]));
      entry["rendered" + suffix] = contact.rendered[i] != 0;
      row.emplace_back(contact.f_W[i].norm());
    }
    if (!side_by_side) row.emplace_back(query.renderings.front().contact.rendered[i] ? "yes" : "no");
    row.insert(row.end(), {p_S.x(), p_S.y(), p_S.z()});
    list.push_back(std::move(entry));
    out.table.rows.push_back(std::move(row));
  }
  out.json["minima"] = std::move(list);
  return out;
}

ResultTable jointTorquesTable(const arm::ArmModel& model, const haptics::QueryResult& query, std::string caption) {
  ResultTable out;
  out.table.caption = std::move(caption);
  out.table.columns = {"Joint"};
  const std::size_t n_renderings = query.renderings.size();
  for (std::size_t k = 0; k < n_renderings; ++k) out.table.columns.push_back(column(query, k, "Contact", "N·m"));
  out.table.columns.push_back("Gravity [N·m]");
  for (std::size_t k = 0; k < n_renderings; ++k) out.table.columns.push_back(column(query, k, "Total", "N·m"));
  for (int j = 0; j < model.numJoints(); ++j) {
    std::vector<reports::Cell> row = {linkName(model, j)};
    for (const haptics::QueryRendering& x : query.renderings) row.emplace_back(x.tau_contact_nm[j]);
    row.emplace_back(query.tau_gravity_nm[j]);
    for (const haptics::QueryRendering& x : query.renderings) row.emplace_back(x.tau_total_nm[j]);
    out.table.rows.push_back(std::move(row));
  }
  out.json["tau_gravity_nm"] = listJson(query.tau_gravity_nm);
  for (std::size_t k = 0; k < n_renderings; ++k) {
    nlohmann::json& at = renderingJson(out.json, query, k);
    at["tau_contact_nm"] = listJson(query.renderings[k].tau_contact_nm);
    at["tau_total_nm"] = listJson(query.renderings[k].tau_total_nm);
  }
  return out;
}

ResultTable linkRecordsTable(const arm::ArmModel& model, const haptics::Scene& scene, const haptics::QueryResult& query,
                             std::string caption) {
  const Eigen::Matrix3d R_SW = haptics::armBasePose(scene, model).linear();
  ResultTable out;
  out.table.caption = std::move(caption);
  out.table.columns = {"Link", "Hand link", "Min distance [mm]", "In contact", "Depth [mm]", "Penetrating"};
  for (std::size_t k = 0; k < query.renderings.size(); ++k) out.table.columns.push_back(column(query, k, "Force", "N"));
  const haptics::ContactData& first = query.renderings.front().contact;
  for (int l = 0; l < model.numJoints(); ++l) {
    const haptics::LinkContactRecord& rec = first.links[static_cast<std::size_t>(l)];
    std::vector<reports::Cell> row = {
        linkName(model, l),
        haptics::isHandLink(model, l) ? "yes" : "no",
        std::isfinite(rec.min_distance_m) ? reports::Cell(rec.min_distance_m * 1e3) : reports::Cell("beyond L"),
        rec.in_contact ? "yes" : "no",
        rec.depth_m * 1e3,
        rec.penetrating ? "yes" : "no"};
    for (const haptics::QueryRendering& x : query.renderings) {
      row.emplace_back(x.contact.link_force_W[static_cast<std::size_t>(l)].norm());
    }
    out.table.rows.push_back(std::move(row));
  }
  for (std::size_t k = 0; k < query.renderings.size(); ++k) {
    const haptics::ContactData& contact = query.renderings[k].contact;
    nlohmann::json list = nlohmann::json::array();
    for (int l = 0; l < model.numJoints(); ++l) {
      const auto i = static_cast<std::size_t>(l);
      const haptics::LinkContactRecord& r = contact.links[i];
      list.push_back({{"link", linkName(model, l)},
                      {"hand_link", haptics::isHandLink(model, l)},
                      {"min_distance_m",
                       std::isfinite(r.min_distance_m) ? nlohmann::json(r.min_distance_m) : nlohmann::json(nullptr)},
                      {"in_contact", r.in_contact},
                      {"penetrating", r.penetrating},
                      {"depth_m", r.depth_m},
                      {"force_n", vectorJson(Eigen::Vector3d(R_SW * contact.link_force_W[i]))}});
    }
    renderingJson(out.json, query, k)["links"] = std::move(list);
  }
  return out;
}

ResultTable solverStatsTable(const plant::SimulationResult& run) {
  ResultTable out;
  out.table.caption = "CVODES statistics (BDF, dense direct solver, analytic Jacobian)";
  out.table.columns = {"Quantity", "Value"};
  out.table.rows = {{"Simulated time [s]", run.simulated_s},
                    {"Wall time [s]", run.wall_s},
                    {"Real-time factor", run.realTimeFactor()},
                    {"Steps", run.stats.steps},
                    {"RHS evaluations", run.stats.rhs_evals},
                    {"Jacobian evaluations", run.stats.jac_evals},
                    {"Error-test failures", run.stats.err_test_fails},
                    {"Nonlinear convergence failures", run.stats.nonlin_conv_fails},
                    {"Re-initialisations", run.stats.reinits},
                    {"Hard-stop events", run.stats.root_events}};
  out.json["solver"] = {{"simulated_s", run.simulated_s},
                        {"wall_s", run.wall_s},
                        {"real_time_factor", run.realTimeFactor()},
                        {"steps", run.stats.steps},
                        {"rhs_evals", run.stats.rhs_evals},
                        {"jac_evals", run.stats.jac_evals},
                        {"err_test_fails", run.stats.err_test_fails},
                        {"nonlin_conv_fails", run.stats.nonlin_conv_fails},
                        {"reinits", run.stats.reinits},
                        {"root_events", run.stats.root_events}};
  return out;
}

}  // namespace fullarm::app
