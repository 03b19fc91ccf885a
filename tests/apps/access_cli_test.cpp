// `fullarm access` end to end: the exit code of each verdict, bad option values, summary.json.

#include "cli_runner.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

namespace {

using fullarm::test::runFullarm;

std::string scene(int env) {
  return std::string(FULLARM_TEST_SOURCE_DIR) + "/scenes/accessibility/env" + std::to_string(env) + ".yaml";
}

TEST(AccessCliTest, UnreachableExitsOneAndWritesTheVerdicts) {
  const std::filesystem::path dir = fullarm::test::cliTempDir("fullarm_access_cli_test", "env2");
  const auto r = runFullarm("access --scene " + scene(2) + " --out " + dir.string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("FALSE POSITIVE"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("access: target 'rim'"), std::string::npos) << r.output;  // progress on stderr
  std::ifstream in(dir / "summary.json");
  const nlohmann::json s = nlohmann::json::parse(in)["results"]["access"];
  EXPECT_EQ(s["contact_allowed"]["verdict"], "unreachable");
  EXPECT_EQ(s["hand_only"]["verdict"], "reachable");
  EXPECT_TRUE(s["hand_only_false_positive"].get<bool>());
  EXPECT_EQ(s["contact_allowed"]["goals"]["valid"], 0);
}

TEST(AccessCliTest, ReachableExitsZeroAndBudgetOutExitsFour) {
  EXPECT_EQ(runFullarm("access --scene " + scene(3)).exit_code, 0);
  const auto r = runFullarm("access --scene " + scene(4) + " --iterations 2");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("budget of 2 ran out"), std::string::npos) << r.output;
}

// At the reached grasp of environment 1 the program gives a finite push; a task that needs less
// passes, one that needs more than the brace posture allows exits 1 (too weak).
TEST(AccessCliTest, ForceDecidesTheExitWhenTheTargetIsReached) {
  const std::filesystem::path dir = fullarm::test::cliTempDir("fullarm_access_cli_test", "force");
  const auto r = runFullarm("access --scene " + scene(1) + " --brace-evaluations 20 --force 1 --out " + dir.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / "summary.json");
  const nlohmann::json f = nlohmann::json::parse(in)["results"]["access"]["force"];
  ASSERT_EQ(f["brace_posture"]["braced"]["status"], "optimal") << f.dump();
  const double best = f["brace_posture"]["braced"]["push_n"].get<double>();
  EXPECT_GT(best, 1.0);
  EXPECT_GE(best, f["at_grasp"]["braced"]["push_n"].get<double>());  // the search starts at the grasp
  EXPECT_TRUE(f["strong_enough"].get<bool>());
  EXPECT_LE(f["evaluations"].get<int>(), 20);
  const auto weak =
      runFullarm("access --scene " + scene(1) + " --brace-evaluations 20 --force " + std::to_string(best * 1.5 + 1.0));
  EXPECT_EQ(weak.exit_code, 1) << weak.output;
  EXPECT_NE(weak.output.find("TOO WEAK"), std::string::npos) << weak.output;
}

// Pushing the wheel towards its valve in environment 4, the forearm resting on the pipe carries
// part of the load: the braced push exceeds the unbraced one by more than a fifth.
TEST(AccessCliTest, BracingOnTheMemberRaisesThePush) {
  const std::filesystem::path dir = fullarm::test::cliTempDir("fullarm_access_cli_test", "brace");
  const auto r =
      runFullarm("access --scene " + scene(4) + " --target rim_push --brace-evaluations 20 --out " + dir.string());
  EXPECT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(dir / "summary.json");
  const nlohmann::json f = nlohmann::json::parse(in)["results"]["access"]["force"];
  ASSERT_EQ(f["at_grasp"]["braced"]["status"], "optimal") << f.dump();
  ASSERT_EQ(f["at_grasp"]["unbraced"]["status"], "optimal") << f.dump();
  EXPECT_GE(f["at_grasp"]["braced"]["push_n"].get<double>(), 1.2 * f["at_grasp"]["unbraced"]["push_n"].get<double>());
  EXPECT_GE(f["at_grasp"]["contacts"].get<int>(), 1);
}

TEST(AccessCliTest, BadValuesExitTwoNamingTheOption) {
  for (const char* bad : {"--max-link-force nan", "--max-link-force inf", "--clearance -0.01", "--max-skin-depth -1",
                          "--seed -3", "--iterations 0"}) {
    const auto r = runFullarm("access --scene " + scene(3) + " " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << "\n" << r.output;
    const std::string option = std::string(bad).substr(0, std::string(bad).find(' '));
    EXPECT_NE(r.output.find(option), std::string::npos) << r.output;
  }
  const auto deep = runFullarm("access --scene " + scene(3) + " --max-skin-depth 0.02");
  EXPECT_EQ(deep.exit_code, 2) << deep.output;
  EXPECT_NE(deep.output.find("max_skin_depth_m"), std::string::npos) << deep.output;
  const auto human = runFullarm("access --scene " + scene(3) + " --human no_such_arm.yaml");
  EXPECT_EQ(human.exit_code, 2) << human.output;
  EXPECT_NE(human.output.find("no_such_arm.yaml"), std::string::npos) << human.output;
  const auto target = runFullarm("access --scene " + scene(3) + " --target stem");
  EXPECT_EQ(target.exit_code, 2) << target.output;
  EXPECT_NE(target.output.find("no target 'stem'"), std::string::npos) << target.output;
}

}  // namespace
