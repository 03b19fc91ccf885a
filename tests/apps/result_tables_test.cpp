// The shared report tables of the fullarm program (apps/result_tables.hpp) on hand-built inputs:
// their columns, rows and summary.json keys, one rendering against modes side by side, points
// and forces turned into the scene frame, and the solver statistics of a plant run.

#include "result_tables.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <set>
#include <string>
#include <variant>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/primitives.hpp"

namespace fullarm::app {
namespace {

using Eigen::Vector3d;
using haptics::RenderMode;

constexpr double kFrameTolerance = 1e-12;  // rotations and translations of unit-sized values

const arm::ArmModel& model() {
  static const arm::ArmModel m = arm::loadArmModel(arm::defaultArmModelPath());
  return m;
}

std::string text(const reports::Cell& c) {
  return std::get<std::string>(c.value());
}
double number(const reports::Cell& c) {
  return std::get<double>(c.value());
}
std::int64_t integer(const reports::Cell& c) {
  return std::get<std::int64_t>(c.value());
}

std::set<std::string> keys(const nlohmann::json& object) {
  std::set<std::string> out;
  for (const auto& [key, value] : object.items()) out.insert(key);
  return out;
}

Vector3d vec(const nlohmann::json& j) {
  return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()};
}

// A scene turned a quarter turn about z (the arm's world x is the scene's y) with its shoulder off
// the origin, two boxes, and a query at the default posture with three minima rendered by hand:
// full-arm renders the two closer than d_f, hand-only only the one on the hand.
class ResultTables : public ::testing::Test {
 protected:
  static constexpr int kArmLink = 4;  // R_WR, not a hand link
  const int hand_link_ = model().tool_link;
  haptics::Scene scene_;
  haptics::CollisionWorld world_{model()};
  haptics::QueryResult query_;

  void SetUp() override {
    scene_.name = "hand_built";
    scene_.shoulder_S_m = Vector3d(1.0, 2.0, 0.5);
    scene_.heading_rad = std::numbers::pi / 2;
    for (const char* name : {"box", "plate"}) {
      haptics::SceneObject object;
      object.name = name;
      object.mesh = haptics::makeBox(Vector3d(0.1, 0.2, 0.3), 1.0);
      object.X_SO.translation() = Vector3d(0.5, name[0] == 'b' ? 0.0 : 0.3, 0.2);
      scene_.objects.push_back(std::move(object));
    }
    world_ = haptics::makeCollisionWorld(scene_, model());

    const int n = model().numJoints();
    query_.q_rad = model().defaultPosture();
    arm::ArmData fk(model());
    arm::computeForwardKinematics(model(), fk, query_.q_rad);
    query_.X_WL = fk.X_WL;
    query_.search = "snch";
    query_.minima = {minimum(kArmLink, 0, 0.004), minimum(hand_link_, 1, 0.006), minimum(kArmLink, 1, 0.02)};
    query_.tau_gravity_nm = Eigen::VectorXd::LinSpaced(n, 1.0, static_cast<double>(n));
  }

  static haptics::LocalMinimum minimum(int link, int object, double d) {
    haptics::LocalMinimum m;
    m.link = link;
    m.object = object;
    m.p_L = Vector3d(0.01, 0.02, -0.05);
    m.p_O = Vector3d(0.05, -0.1, 0.15);
    m.distance_m = d;
    return m;
  }

  void addRendering(RenderMode mode) {
    const int n = model().numJoints();
    haptics::QueryRendering& x = query_.renderings.emplace_back(model(), mode, 3);
    const bool full = mode == RenderMode::kFullArm;
    x.contact.f_W[0] = full ? Vector3d(12.0, 0.0, 0.0) : Vector3d::Zero();
    x.contact.f_W[1] = Vector3d(0.0, 0.0, 8.0);
    x.contact.rendered[0] = full ? 1 : 0;
    x.contact.rendered[1] = 1;
    x.contact.link_force_W[kArmLink] = x.contact.f_W[0];
    x.contact.link_force_W[static_cast<std::size_t>(hand_link_)] = x.contact.f_W[1];
    x.contact.links[kArmLink] = {true, false, 0.004, 0.006};
    x.contact.links[static_cast<std::size_t>(hand_link_)] = {true, true, 0.0, 0.01};
    x.contact.active_springs = full ? 2 : 1;
    x.tau_contact_nm = Eigen::VectorXd::Constant(n, full ? 0.5 : 0.25);
    x.tau_total_nm = x.tau_contact_nm + query_.tau_gravity_nm;
  }

  // Scene-frame coordinates by the scene's definition: the shoulder plus the heading's rotation
  // of the offset from the arm's DH frame 0 origin.
  Vector3d toScene(const Vector3d& p_W) const {
    return scene_.shoulder_S_m +
           Eigen::AngleAxisd(scene_.heading_rad, Vector3d::UnitZ()) * (p_W - model().X_WB.translation());
  }
  static Vector3d rotateToScene(const Vector3d& f_W) { return {-f_W.y(), f_W.x(), f_W.z()}; }
};

TEST_F(ResultTables, MinimaOfOneRenderingHaveTheirRenderedColumnAndObjectPoints) {
  addRendering(RenderMode::kFullArm);
  const ResultTable t = minimaTable(model(), scene_, world_, query_, "Minima");
  EXPECT_EQ(t.table.caption, "Minima");
  EXPECT_EQ(t.table.columns, (std::vector<std::string>{"Link", "Object", "Distance [mm]", "Force [N]", "Rendered",
                                                       "x [m]", "y [m]", "z [m]"}));
  ASSERT_EQ(t.table.rows.size(), 3u);
  ASSERT_EQ(keys(t.json), (std::set<std::string>{"minima"}));
  const nlohmann::json& list = t.json["minima"];
  ASSERT_EQ(list.size(), 3u);
  const std::string names[] = {"R_WR", model().joints[static_cast<std::size_t>(hand_link_)].name, "R_WR"};
  const std::string objects[] = {"box", "plate", "plate"};
  const double force_n[] = {12.0, 8.0, 0.0};
  for (std::size_t i = 0; i < 3; ++i) {
    const std::vector<reports::Cell>& row = t.table.rows[i];
    ASSERT_EQ(row.size(), t.table.columns.size());
    EXPECT_EQ(text(row[0]), names[i]);
    EXPECT_EQ(text(row[1]), objects[i]);
    EXPECT_DOUBLE_EQ(number(row[2]), query_.minima[i].distance_m * 1e3);
    EXPECT_DOUBLE_EQ(number(row[3]), force_n[i]);
    EXPECT_EQ(text(row[4]), i < 2 ? "yes" : "no");
    const haptics::LocalMinimum& m = query_.minima[i];
    const Vector3d p_S = toScene(query_.X_WL[static_cast<std::size_t>(m.link)] * m.p_L);
    for (int c = 0; c < 3; ++c) EXPECT_NEAR(number(row[5 + static_cast<std::size_t>(c)]), p_S[c], kFrameTolerance);

    const nlohmann::json& e = list[i];
    EXPECT_EQ(keys(e), (std::set<std::string>{"link", "object", "distance_m", "point_link_scene_m",
                                              "point_object_scene_m", "force_n", "rendered"}));
    EXPECT_EQ(e["link"], names[i]);
    EXPECT_EQ(e["object"], objects[i]);
    EXPECT_EQ(e["distance_m"].get<double>(), m.distance_m);
    EXPECT_LE((vec(e["point_link_scene_m"]) - p_S).norm(), kFrameTolerance);
    // The object point: the object's pose in the scene, whatever the arm's placement.
    const Vector3d q_S = scene_.objects[static_cast<std::size_t>(m.object)].X_SO * m.p_O;
    EXPECT_LE((vec(e["point_object_scene_m"]) - q_S).norm(), kFrameTolerance);
    EXPECT_LE((vec(e["force_n"]) - rotateToScene(query_.renderings[0].contact.f_W[i])).norm(), kFrameTolerance);
    EXPECT_EQ(e["rendered"].get<bool>(), i < 2);
  }
}

TEST_F(ResultTables, MinimaOfModesSideBySideHaveAForceColumnPerModeAndTheHandLink) {
  addRendering(RenderMode::kFullArm);
  addRendering(RenderMode::kHandOnly);
  const ResultTable t = minimaTable(model(), scene_, world_, query_, "Minima side by side");
  EXPECT_EQ(t.table.columns,
            (std::vector<std::string>{"Link", "Hand link", "Object", "Distance [mm]", "Force full-arm [N]",
                                      "Force hand-only [N]", "x [m]", "y [m]", "z [m]"}));
  ASSERT_EQ(t.table.rows.size(), 3u);
  EXPECT_EQ(text(t.table.rows[0][1]), "no");
  EXPECT_EQ(text(t.table.rows[1][1]), "yes");
  EXPECT_DOUBLE_EQ(number(t.table.rows[0][4]), 12.0);
  EXPECT_DOUBLE_EQ(number(t.table.rows[0][5]), 0.0);
  EXPECT_DOUBLE_EQ(number(t.table.rows[1][5]), 8.0);
  const nlohmann::json& e = t.json["minima"][0];
  EXPECT_EQ(keys(e), (std::set<std::string>{"link", "hand_link", "object", "distance_m", "point_link_scene_m",
                                            "force_full_arm_n", "force_hand_only_n", "rendered_full_arm",
                                            "rendered_hand_only"}));
  EXPECT_FALSE(e["hand_link"].get<bool>());
  EXPECT_TRUE(e["rendered_full_arm"].get<bool>());
  EXPECT_FALSE(e["rendered_hand_only"].get<bool>());
  EXPECT_LE((vec(e["force_full_arm_n"]) - Vector3d(0.0, 12.0, 0.0)).norm(), kFrameTolerance);
  EXPECT_EQ(vec(e["force_hand_only_n"]).norm(), 0.0);
}

TEST_F(ResultTables, JointTorquesKeepGravityOnceAndContactAndTotalPerRendering) {
  addRendering(RenderMode::kFullArm);
  const int n = model().numJoints();
  const ResultTable one = jointTorquesTable(model(), query_, "Joint torques");
  EXPECT_EQ(one.table.columns, (std::vector<std::string>{"Joint", "Contact [N·m]", "Gravity [N·m]", "Total [N·m]"}));
  ASSERT_EQ(one.table.rows.size(), static_cast<std::size_t>(n));
  for (int j = 0; j < n; ++j) {
    const std::vector<reports::Cell>& row = one.table.rows[static_cast<std::size_t>(j)];
    EXPECT_EQ(text(row[0]), model().joints[static_cast<std::size_t>(j)].name);
    EXPECT_EQ(number(row[1]), 0.5);
    EXPECT_EQ(number(row[2]), j + 1.0);
    EXPECT_EQ(number(row[3]), j + 1.5);
  }
  EXPECT_EQ(keys(one.json), (std::set<std::string>{"tau_contact_nm", "tau_gravity_nm", "tau_total_nm"}));
  EXPECT_EQ(one.json["tau_gravity_nm"].size(), static_cast<std::size_t>(n));
  EXPECT_EQ(one.json["tau_total_nm"][2].get<double>(), 3.5);

  addRendering(RenderMode::kHandOnly);
  const ResultTable two = jointTorquesTable(model(), query_, "Side by side");
  EXPECT_EQ(two.table.columns,
            (std::vector<std::string>{"Joint", "Contact full-arm [N·m]", "Contact hand-only [N·m]", "Gravity [N·m]",
                                      "Total full-arm [N·m]", "Total hand-only [N·m]"}));
  EXPECT_EQ(number(two.table.rows[3][2]), 0.25);
  EXPECT_EQ(number(two.table.rows[3][5]), 4.25);
  EXPECT_EQ(keys(two.json), (std::set<std::string>{"tau_gravity_nm", "full_arm", "hand_only"}));
  EXPECT_EQ(keys(two.json["hand_only"]), (std::set<std::string>{"tau_contact_nm", "tau_total_nm"}));
  EXPECT_EQ(two.json["hand_only"]["tau_contact_nm"][0].get<double>(), 0.25);
  EXPECT_EQ(two.json["full_arm"]["tau_total_nm"][0].get<double>(), 1.5);
}

TEST_F(ResultTables, LinkRecordsHaveOneRowPerLinkAndTheSummedForceInTheSceneFrame) {
  addRendering(RenderMode::kFullArm);
  addRendering(RenderMode::kHandOnly);
  const int n = model().numJoints();
  const ResultTable t = linkRecordsTable(model(), scene_, query_, "Links");
  EXPECT_EQ(t.table.columns,
            (std::vector<std::string>{"Link", "Hand link", "Min distance [mm]", "In contact", "Depth [mm]",
                                      "Penetrating", "Force full-arm [N]", "Force hand-only [N]"}));
  ASSERT_EQ(t.table.rows.size(), static_cast<std::size_t>(n));
  const std::vector<reports::Cell>& arm_row = t.table.rows[kArmLink];
  EXPECT_EQ(text(arm_row[0]), "R_WR");
  EXPECT_EQ(text(arm_row[1]), "no");
  EXPECT_DOUBLE_EQ(number(arm_row[2]), 4.0);
  EXPECT_EQ(text(arm_row[3]), "yes");
  EXPECT_DOUBLE_EQ(number(arm_row[4]), 6.0);
  EXPECT_EQ(text(arm_row[5]), "no");
  EXPECT_DOUBLE_EQ(number(arm_row[6]), 12.0);
  EXPECT_DOUBLE_EQ(number(arm_row[7]), 0.0);
  EXPECT_EQ(text(t.table.rows[static_cast<std::size_t>(hand_link_)][5]), "yes");
  EXPECT_EQ(text(t.table.rows[0][2]), "beyond L");  // no minimum on the first link

  EXPECT_EQ(keys(t.json), (std::set<std::string>{"full_arm", "hand_only"}));
  const nlohmann::json& links = t.json["full_arm"]["links"];
  ASSERT_EQ(links.size(), static_cast<std::size_t>(n));
  EXPECT_EQ(keys(links[0]), (std::set<std::string>{"link", "hand_link", "min_distance_m", "in_contact", "penetrating",
                                                   "depth_m", "force_n"}));
  EXPECT_TRUE(links[0]["min_distance_m"].is_null());
  EXPECT_EQ(links[kArmLink]["min_distance_m"].get<double>(), 0.004);
  EXPECT_LE((vec(links[kArmLink]["force_n"]) - Vector3d(0.0, 12.0, 0.0)).norm(), kFrameTolerance);
  EXPECT_EQ(vec(t.json["hand_only"]["links"][kArmLink]["force_n"]).norm(), 0.0);

  query_.renderings.pop_back();
  const ResultTable one = linkRecordsTable(model(), scene_, query_, "Links");
  EXPECT_EQ(one.table.columns.back(), "Force [N]");
  EXPECT_EQ(keys(one.json), (std::set<std::string>{"links"}));
}

TEST(SolverStatsTable, RowsAndKeysCarryTheRunsCounters) {
  plant::SimulationResult run;
  run.simulated_s = 2.0;
  run.wall_s = 0.5;
  run.stats.steps = 101;
  run.stats.rhs_evals = 202;
  run.stats.jac_evals = 33;
  run.stats.err_test_fails = 4;
  run.stats.nonlin_conv_fails = 5;
  run.stats.reinits = 6;
  run.stats.root_events = 7;
  const ResultTable t = solverStatsTable(run);
  EXPECT_EQ(t.table.columns, (std::vector<std::string>{"Quantity", "Value"}));
  ASSERT_EQ(t.table.rows.size(), 10u);
  EXPECT_EQ(text(t.table.rows[0][0]), "Simulated time [s]");
  EXPECT_EQ(number(t.table.rows[0][1]), 2.0);
  EXPECT_EQ(number(t.table.rows[2][1]), 4.0);  // real-time factor
  EXPECT_EQ(integer(t.table.rows[3][1]), 101);
  EXPECT_EQ(integer(t.table.rows[5][1]), 33);
  EXPECT_EQ(integer(t.table.rows[9][1]), 7);
  EXPECT_EQ(keys(t.json), (std::set<std::string>{"solver"}));
  const nlohmann::json& s = t.json["solver"];
  EXPECT_EQ(keys(s),
            (std::set<std::string>{"simulated_s", "wall_s", "real_time_factor", "steps", "rhs_evals", "jac_evals",
                                   "err_test_fails", "nonlin_conv_fails", "reinits", "root_events"}));
  EXPECT_EQ(s["real_time_factor"].get<double>(), 4.0);
  EXPECT_EQ(s["rhs_evals"].get<long>(), 202);
  EXPECT_EQ(s["nonlin_conv_fails"].get<long>(), 5);
}

TEST(MergeJson, MergesObjectsAndReplacesOtherValues) {
  nlohmann::json target = {{"a", 1}, {"mode", {{"fault", false}, {"links", {1, 2}}}}};
  mergeJson(target, {{"b", 2}, {"mode", {{"tau", {3.0}}, {"links", {4}}}}});
  EXPECT_EQ(target, nlohmann::json({{"a", 1}, {"b", 2}, {"mode", {{"fault", false}, {"links", {4}}, {"tau", {3.0}}}}}));
}

}  // namespace
}  // namespace fullarm::app
