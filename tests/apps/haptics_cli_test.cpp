// `fullarm haptics query` end to end: exit codes and messages on bad input, summary.json of the
// valve scene at its reach posture, and what hand-only mode changes against full-arm mode.

#include "cli_runner.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>

namespace {

using Result = fullarm::test::CliResult;
using fullarm::test::runFullarm;

std::filesystem::path tempDir(const std::string& name) {
  return fullarm::test::cliTempDir("fullarm_haptics_cli_test", name);
}

std::string source(const std::string& rel) {
  return std::string(FULLARM_TEST_SOURCE_DIR) + "/" + rel;
}

std::string sceneText() {
  std::ifstream in(source("scenes/valve_wall.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

// The scene's reach_valve posture (scenes/valve_wall.yaml).
const std::string kReach = "--q 1.2,-0.3,0,0.7,0,0,0";

std::string query(const std::string& scene, const std::string& rest) {
  return "haptics query --scene " + scene + " " + rest;
}

nlohmann::json readHaptics(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in)["results"]["haptics"];
}

struct BadQCase {
  const char* name;
  const char* q;
  const char* expected;  // part of the message
};

class HapticsCliBadQ : public ::testing::TestWithParam<BadQCase> {};

TEST_P(HapticsCliBadQ, ExitsTwoNamingTheProblem) {
  const BadQCase& c = GetParam();
  const Result r = runFullarm(query(source("scenes/valve_wall.yaml"), std::string("--q ") + c.q));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--q"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
}

// The DTS model has 7 arm joints and 3 hand joints: up to 10 values are a posture, 11 are not.
INSTANTIATE_TEST_SUITE_P(Cases, HapticsCliBadQ,
                         ::testing::Values(BadQCase{"non_numeric", "1.2,abc,0,0.7,0,0,0", "'abc'"},
                                           BadQCase{"too_many", "1,0,0,1,0,0,0,0,0,0,0", "got 11"},
                                           BadQCase{"out_of_range", "1.2,-0.3,0,9.0,0,0,0", "outside the joint range"},
                                           BadQCase{"not_finite", "1.2,-0.3,0,nan,0,0,0", "element 3"}),
                         [](const ::testing::TestParamInfo<BadQCase>& param_info) {
                           return std::string(param_info.param.name);
                         });

TEST(HapticsCli, MissingSceneFileExitsTwoNamingIt) {
  const std::string missing = (tempDir("missing") / "no_such_scene.yaml").string();
  const Result r = runFullarm(query(missing, kReach));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("no_such_scene.yaml"), std::string::npos) << r.output;
}

// A scene with a wrong value, an unknown key, a YAML syntax error and a truncated file: exit 2
// with the file name and the key path (or line), never a crash.
struct BadSceneCase {
  const char* name;
  const char* from;      // text of valve_wall.yaml to replace (first occurrence)
  const char* to;        // replacement
  const char* expected;  // part of the message
  int truncate_at = 0;   // if > 0: keep only this percentage of the file (after the replacement)
};

class HapticsCliBadScene : public ::testing::TestWithParam<BadSceneCase> {};

TEST_P(HapticsCliBadScene, ExitsTwoNamingFileAndKey) {
  const BadSceneCase& c = GetParam();
  std::string yaml = sceneText();
  const std::size_t at = yaml.find(c.from);
  ASSERT_NE(at, std::string::npos) << "fixture text not found: " << c.from;
  yaml.replace(at, std::string(c.from).size(), c.to);
  if (c.truncate_at > 0) yaml.resize(yaml.size() * static_cast<std::size_t>(c.truncate_at) / 100);
  // The copy's mesh paths point at the source tree's meshes.
  for (std::size_t pos = yaml.find("file: meshes/"); pos != std::string::npos; pos = yaml.find("file: meshes/", pos)) {
    yaml.replace(pos, 6, "file: " + source("scenes") + "/");
  }
  const auto file = tempDir(std::string("bad_scene_") + c.name) / (std::string(c.name) + ".yaml");
  std::ofstream(file) << yaml;
  const Result r = runFullarm(query(file.string(), kReach));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(file.filename().string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, HapticsCliBadScene,
    ::testing::Values(BadSceneCase{"short_vector", "shoulder_m: [0.283, 0.0, 1.40]", "shoulder_m: [0.283, 0.0]",
                                   "shoulder_m"},
                      BadSceneCase{"unknown_key", "heading_deg: 0.0", "heading_degrees: 0.0", "heading_degrees"},
                      BadSceneCase{"yaml_syntax", "name: valve_wall", "name: [valve_wall", "YAML syntax error"},
                      BadSceneCase{"truncated", "schema_version", "schema_version", "YAML syntax error", 36},
                      BadSceneCase{"missing_mesh", "five_dice_wall.dae", "no_such_mesh.dae", "no_such_mesh.dae"}),
    [](const ::testing::TestParamInfo<BadSceneCase>& param_info) { return std::string(param_info.param.name); });

// The reach posture puts the wrist and hand within the force threshold of the truss and the
// valve: the query exits 0 and summary.json holds the minima, forces and torques, with
// tau_total = tau_contact + tau_gravity joint by joint.
TEST(HapticsCli, ValveSceneAtTheReachPostureWritesSummary) {
  const auto dir = tempDir("reach_full");
  const Result r = runFullarm(query(source("scenes/valve_wall.yaml"), kReach + " --out " + dir.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("minima within L"), std::string::npos) << r.output;
  const nlohmann::json h = readHaptics(dir);
  EXPECT_EQ(h["scene"], "valve_wall");
  EXPECT_EQ(h["mode"], "full-arm");
  EXPECT_EQ(h["search"], "snch");
  EXPECT_FALSE(h["fault"].get<bool>());
  ASSERT_GE(h["minima"].size(), 1u);
  const double cutoff = h["cutoff_m"].get<double>();
  for (const auto& m : h["minima"]) {
    EXPECT_GE(m["distance_m"].get<double>(), 0.0);
    EXPECT_LE(m["distance_m"].get<double>(), cutoff);
    EXPECT_EQ(m["force_n"].size(), 3u);
    EXPECT_EQ(m["point_link_scene_m"].size(), 3u);
    EXPECT_EQ(m["point_object_scene_m"].size(), 3u);
    // The distance is the gap between the two reported points.
    double gap2 = 0.0;
    for (int k = 0; k < 3; ++k) {
      const double d = m["point_link_scene_m"][k].get<double>() - m["point_object_scene_m"][k].get<double>();
      gap2 += d * d;
    }
    EXPECT_NEAR(std::sqrt(gap2), m["distance_m"].get<double>(), 1e-6);
  }
  const auto& c = h["tau_contact_nm"];
  const auto& g = h["tau_gravity_nm"];
  const auto& t = h["tau_total_nm"];
  ASSERT_EQ(c.size(), g.size());
  ASSERT_EQ(c.size(), t.size());
  for (std::size_t j = 0; j < c.size(); ++j) {
    EXPECT_TRUE(std::isfinite(c[j].get<double>()));
    EXPECT_NEAR(t[j].get<double>(), c[j].get<double>() + g[j].get<double>(), 1e-9);
  }
  EXPECT_EQ(h["links"].size(), c.size());
  EXPECT_TRUE(std::filesystem::is_regular_file(dir / "report.html"));
}

// Hand-only mode renders forces only at minima on hand links, while the contact records still
// cover every link; the contact torques therefore differ from full-arm mode, gravity does not.
TEST(HapticsCli, HandOnlyRendersOnlyHandLinkMinima) {
  const auto full_dir = tempDir("reach_full_cmp");
  const auto hand_dir = tempDir("reach_hand_cmp");
  const std::string scene = source("scenes/valve_wall.yaml");
  const Result rf = runFullarm(query(scene, kReach + " --out " + full_dir.string()));
  const Result rh = runFullarm(query(scene, kReach + " --mode hand-only --out " + hand_dir.string()));
  ASSERT_EQ(rf.exit_code, 0) << rf.output;
  ASSERT_EQ(rh.exit_code, 0) << rh.output;
  const nlohmann::json f = readHaptics(full_dir);
  const nlohmann::json h = readHaptics(hand_dir);
  EXPECT_EQ(h["mode"], "hand-only");
  std::set<std::string> hand_links;
  for (const auto& l : h["links"]) {
    if (l["hand_link"].get<bool>()) hand_links.insert(l["link"].get<std::string>());
  }
  ASSERT_FALSE(hand_links.empty());
  // Same search, same minima in both modes.
  ASSERT_EQ(f["minima"].size(), h["minima"].size());
  int full_rendered_non_hand = 0;
  int hand_rendered = 0;
  for (std::size_t i = 0; i < h["minima"].size(); ++i) {
    const auto& mh = h["minima"][i];
    const auto& mf = f["minima"][i];
    EXPECT_EQ(mh["link"], mf["link"]);
    EXPECT_DOUBLE_EQ(mh["distance_m"].get<double>(), mf["distance_m"].get<double>());
    const bool is_hand = hand_links.count(mh["link"].get<std::string>()) > 0;
    if (mh["rendered"].get<bool>()) {
      ++hand_rendered;
      EXPECT_TRUE(is_hand) << "hand-only rendered a minimum on " << mh["link"];
    } else {
      for (int k = 0; k < 3; ++k) EXPECT_EQ(mh["force_n"][k].get<double>(), 0.0);
    }
    if (!is_hand && mf["rendered"].get<bool>()) ++full_rendered_non_hand;
  }
  EXPECT_GE(hand_rendered, 1);
  // The reach posture was chosen so that the forearm side touches the truss: full-arm renders it.
  EXPECT_GE(full_rendered_non_hand, 1);
  // Records: a non-hand link in contact is recorded in hand-only mode, as in full-arm mode.
  ASSERT_EQ(f["links"].size(), h["links"].size());
  int non_hand_in_contact = 0;
  for (std::size_t l = 0; l < h["links"].size(); ++l) {
    EXPECT_EQ(h["links"][l]["in_contact"], f["links"][l]["in_contact"]);
    if (h["links"][l]["in_contact"].get<bool>() && !h["links"][l]["hand_link"].get<bool>()) ++non_hand_in_contact;
  }
  EXPECT_GE(non_hand_in_contact, 1);
  // Torques: gravity equal, contact differs somewhere.
  double max_contact_diff = 0.0;
  for (std::size_t j = 0; j < f["tau_contact_nm"].size(); ++j) {
    EXPECT_DOUBLE_EQ(f["tau_gravity_nm"][j].get<double>(), h["tau_gravity_nm"][j].get<double>());
    max_contact_diff = std::max(max_contact_diff,
                                std::abs(f["tau_contact_nm"][j].get<double>() - h["tau_contact_nm"][j].get<double>()));
  }
  EXPECT_GT(max_contact_diff, 1e-3);
}

}  // namespace
