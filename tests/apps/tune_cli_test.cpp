// `fullarm tune` end to end: the tuned gains file loads with the gains loader `validate` uses,
// summary.json carries the per-joint results, bad input exits 2 with a message.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"

namespace {

struct Result {
  int exit_code = -1;
  std::string output;
};

Result runFullarm(const std::string& args) {
  const std::string command = std::string(FULLARM_EXE) + " " + args + " 2>&1";
  Result r;
  FILE* pipe = popen(command.c_str(), "r");
  if (pipe == nullptr) return r;
  std::array<char, 4096> buffer{};
  std::size_t n = 0;
  while ((n = fread(buffer.data(), 1, buffer.size(), pipe)) > 0) r.output.append(buffer.data(), n);
  const int status = pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::filesystem::path tempDir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / "fullarm_tune_cli_test" / name;
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

TEST(TuneCli, WritesLoadableGainsAndSummary) {
  const auto dir = tempDir("eb");
  const Result r = runFullarm("tune --joints EB --global-evals 40 --local-evals 30 --rounds 1 --out " + dir.string());
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  const fullarm::controllers::GainsConfig gains = fullarm::controllers::loadGainsConfig(dir / "gains.yaml", model);
  EXPECT_EQ(gains.joints.size(), 7u);
  std::ifstream in(dir / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  const nlohmann::json& joints = summary["results"]["tune"]["joints"];
  ASSERT_EQ(joints.size(), 1u);
  EXPECT_EQ(joints[0]["joint"], "R_EB");
  EXPECT_EQ(summary["verdict"]["pass"].get<bool>(), r.exit_code == 0);
  // The tuned joint in the file is the one the summary reports.
  const auto& eb = gains.joints[static_cast<std::size_t>(fullarm::controllers::findGainsJoint(gains, "EB"))];
  EXPECT_DOUBLE_EQ(eb.impedance.inertia_kgm2, joints[0]["tuned_gains"]["inertia_kgm2"].get<double>());
  EXPECT_TRUE(std::filesystem::exists(dir / "report.html"));
}

TEST(TuneCli, UnknownJointIsBadInput) {
  const Result r = runFullarm("tune --joints XX --out " + tempDir("bad").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("XX"), std::string::npos) << r.output;
}

TEST(TuneCli, ZeroRoundsIsBadInput) {
  const Result r = runFullarm("tune --rounds 0 --out " + tempDir("rounds").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--rounds"), std::string::npos) << r.output;
}

}  // namespace
