#pragma once
// The tables that more than one command writes, each with the summary.json keys that carry the
// same data: the minima, joint torques and per-link contact records of a haptic query (`haptics
// query`, the demo's haptics step) and the solver statistics of a plant run (`plant simulate`,
// the demo's plant step). One function builds each, so the commands write them alike.

#include <cstddef>
#include <string>

#include <nlohmann/json.hpp>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/query.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/plant/simulation.hpp"
#include "fullarm/reports/table.hpp"

namespace fullarm::app {

/// A report table and the summary.json keys with the same data.
struct ResultTable {
  reports::Table table;
  /// An object whose members go into the command's results object (mergeJson).
  nlohmann::json json = nlohmann::json::object();
};

/// Adds the members of the object `part` to the object `target`; a member that is an object in
/// both is merged the same way, any other replaces the target's.
void mergeJson(nlohmann::json& target, const nlohmann::json& part);

/// Key of a rendering mode's object in summary.json: "full_arm", "hand_only".
std::string modeKey(haptics::RenderMode mode);
/// A rendering mode as the command line and the reports name it: "full-arm", "hand-only".
std::string modeLabel(haptics::RenderMode mode);

/// Where the keys of rendering `index` of `query` go in `json`: `json` itself when the query has
/// one rendering, `json[modeKey(mode)]` when it has several (modes side by side).
nlohmann::json& renderingJson(nlohmann::json& json, const haptics::QueryResult& query, std::size_t index);

/// The minima of a query, one row and one `minima[]` entry each, points and forces in the scene
/// frame S. With one rendering: columns Link, Object, Distance [mm], Force [N], Rendered, x, y,
/// z [m] (the link point); entries `link`, `object`, `distance_m`, `point_link_scene_m`,
/// `point_object_scene_m`, `force_n`, `rendered`. With several (modes side by side): columns
/// Link, Hand link, Object, Distance [mm], `Force <mode> [N]` per rendering, x, y, z [m];
/// entries `link`, `hand_link`, `object`, `distance_m`, `point_link_scene_m`, `force_<mode>_n`
/// and `rendered_<mode>` per rendering (mode as modeKey).
/// @param world the query's collision world (object poses)
ResultTable minimaTable(const arm::ArmModel& model, const haptics::Scene& scene, const haptics::CollisionWorld& world,
                        const haptics::QueryResult& query, std::string caption);

/// The joint torques of a query, one row per joint: Joint, `Contact [N·m]`, Gravity [N·m],
/// `Total [N·m]` (with several renderings one Contact and one Total column per mode, "Contact
/// full-arm [N·m]"); keys `tau_gravity_nm` and, in each rendering's object (renderingJson),
/// `tau_contact_nm` and `tau_total_nm`.
ResultTable jointTorquesTable(const arm::ArmModel& model, const haptics::QueryResult& query, std::string caption);

/// The per-link contact records of a query, one row per link: Link, Hand link, Min distance
/// [mm] ("beyond L" without a minimum), In contact, Depth [mm], Penetrating (the records do not
/// depend on the mode: the first rendering's), then the magnitude of the summed force on the
/// link per rendering ("Force [N]", or "Force <mode> [N]" with several); key `links[]` in each
/// rendering's object: `link`, `hand_link`, `min_distance_m` (null beyond L), `in_contact`,
/// `penetrating`, `depth_m`, `force_n` (summed force on the link, scene frame).
ResultTable linkRecordsTable(const arm::ArmModel& model, const haptics::Scene& scene, const haptics::QueryResult& query,
                             std::string caption);

/// The solver statistics of a plant run: rows Simulated time, Wall time, Real-time factor,
/// Steps, RHS and Jacobian evaluations, error-test and nonlinear convergence failures,
/// re-initialisations, hard-stop events; key `solver` with `simulated_s`, `wall_s`,
/// `real_time_factor`, `steps`, `rhs_evals`, `jac_evals`, `err_test_fails`, `nonlin_conv_fails`,
/// `reinits`, `root_events`.
ResultTable solverStatsTable(const plant::SimulationResult& run);

}  // namespace fullarm::app
