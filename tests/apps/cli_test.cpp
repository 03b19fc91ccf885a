// The fullarm program end to end: exit codes, messages on bad input, output folders.

#include "cli_runner.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>

namespace {

using Result = fullarm::test::CliResult;
using fullarm::test::runFullarm;

std::filesystem::path tempDir(const std::string& name) {
  return fullarm::test::cliTempDir("fullarm_cli_test", name);
}

std::string source(const std::string& rel) {
  return std::string(FULLARM_TEST_SOURCE_DIR) + "/" + rel;
}

// Writes dir/arm.yaml: the default model with the first `from` replaced by `to`.
std::filesystem::path editedConfig(const std::filesystem::path& dir, const std::string& from, const std::string& to) {
  std::ifstream in(source("config/dts_master.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  const std::size_t at = yaml.find(from);
  EXPECT_NE(at, std::string::npos) << "fixture text not found: " << from;
  if (at != std::string::npos) yaml.replace(at, from.size(), to);
  const auto file = dir / "arm.yaml";
  std::ofstream(file) << yaml;
  return file;
}

TEST(Cli, HelpOnEveryCommand) {
  for (const char* args : {"--help", "arm --help", "arm show --help", "demo --help"}) {
    const Result r = runFullarm(args);
    EXPECT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    EXPECT_NE(r.output.find("Usage"), std::string::npos) << args;
  }
}

TEST(Cli, ArmShowPrintsChainLengthsMassReachAndPose) {
  const Result r = runFullarm("arm show --config " + source("config/dts_master.yaml"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* text : {"R_SFE", "R_FAA", "upper arm 0.2870 m", "forearm 0.2781 m", "Total mass: 17.50 kg", "Reach",
                           "Hand point at q: p_W = (0.4041, 0.3631, 0.0112) m"}) {
    EXPECT_NE(r.output.find(text), std::string::npos) << "missing '" << text << "' in\n" << r.output;
  }
}

TEST(Cli, UnknownSubcommandFails) {
  const Result r = runFullarm("arm wiggle");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

TEST(Cli, NegativeLengthIsRejected) {
  const Result r = runFullarm("arm show --upper-arm-length -0.3");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--upper-arm-length"), std::string::npos) << r.output;
}

TEST(Cli, NonNumericLengthIsRejected) {
  const Result r = runFullarm("arm show --forearm-length long");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--forearm-length"), std::string::npos) << r.output;
}

TEST(Cli, PostureOutsideRangeIsRejected) {
  const Result r = runFullarm("arm show --q \"0, -0.3, 0, 3.0\"");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--q: element 3 (R_EB) = 3.000000 rad is outside the joint range"), std::string::npos)
      << r.output;
}

TEST(Cli, GarbagePostureIsRejected) {
  const Result r = runFullarm("arm show --q \"0, abc\"");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--q: element 1 is 'abc'"), std::string::npos) << r.output;
}

// The loader's error cases through the program: each must exit 2 and print the file, the key
// path and what was expected (one test per case).
struct BadConfigCase {
  const char* name;
  const char* from;
  const char* to;
  const char* key_path;
  const char* expected;
};

class CliBadConfig : public ::testing::TestWithParam<BadConfigCase> {};

TEST_P(CliBadConfig, NamesFileKeyAndExpectationAndExitsNonZero) {
  const BadConfigCase& c = GetParam();
  const auto dir = tempDir(std::string("bad_") + c.name);
  const auto file = editedConfig(dir, c.from, c.to);
  const Result r = runFullarm("arm show --config " + file.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(file.string()), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.key_path), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
}

INSTANTIATE_TEST_SUITE_P(
    Cases, CliBadConfig,
    ::testing::Values(
        BadConfigCase{"missing_key", "    default_rad: -0.30\n", "", "joints[1]", "missing required key 'default_rad'"},
        BadConfigCase{"wrong_type", "mass_kg: 6.8", "mass_kg: heavy", "joints[2].link.mass_kg",
                      "expected a finite number (kg), got 'heavy'"},
        BadConfigCase{"negative_mass", "mass_kg: 3.36", "mass_kg: -1.0", "joints[4].link.mass_kg",
                      "expected a mass >= 0 kg"},
        BadConfigCase{"not_positive_definite", "{xx: 0.050926, yy: 0.050926, zz: 0.0085,",
                      "{xx: 0.050926, yy: 0.050926, zz: -0.0085,", "joints[2].link.inertia_kgm2",
                      "must be positive definite"},
        BadConfigCase{"min_above_max", "{min_rad: 0.586132, max_rad: 2.208897,", "{min_rad: 2.3, max_rad: 0.586132,",
                      "joints[3].limits", "expected min_rad < max_rad"},
        BadConfigCase{"unknown_key", "    default_rad: 1.57\n", "    default_rad: 1.57\n    stiffnes: 3\n",
                      "joints[3].stiffnes", "unknown key"}),
    [](const ::testing::TestParamInfo<BadConfigCase>& case_info) { return std::string(case_info.param.name); });

TEST(Cli, FailingVerdictExitsOne) {
  // A shoulder that can only deliver 1 N m cannot hold the arm at the default posture.
  const auto dir = tempDir("weak_shoulder");
  const auto file = editedConfig(dir, "velocity_radps: 3.0, torque_nm: 99.6}", "velocity_radps: 3.0, torque_nm: 1.0}");
  const Result r = runFullarm("arm show --config " + file.string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("BEYOND the joint torque limits"), std::string::npos) << r.output;
  std::ifstream summary_in(dir / "out" / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(summary_in);
  EXPECT_EQ(summary["verdict"]["pass"], false);
}

TEST(Cli, MissingConfigFileIsRejected) {
  const Result r = runFullarm("arm show --config /nonexistent/arm.yaml");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("/nonexistent/arm.yaml"), std::string::npos) << r.output;
}

TEST(Cli, ArmSizeChangesTheReportedLengths) {
  const Result r = runFullarm("arm show --upper-arm-length 0.33 --forearm-length 0.26");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("upper arm 0.3300 m, forearm 0.2600 m"), std::string::npos) << r.output;
}

TEST(Cli, ArmShowWritesSummaryAndReport) {
  const auto dir = tempDir("arm_show");
  const Result r = runFullarm("arm show --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ASSERT_TRUE(std::filesystem::exists(dir / "report.html"));
  std::ifstream in(dir / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["subcommand"], "arm show");
  EXPECT_EQ(summary["verdict"]["pass"], true);
  EXPECT_EQ(summary["results"]["arm"]["num_joints"], 10);
  EXPECT_NEAR(summary["results"]["arm"]["upper_arm_length_m"].get<double>(), 0.287, 1e-12);
  EXPECT_GT(summary["results"]["arm"]["reach_m"].get<double>(), 0.5);
  EXPECT_LT(summary["results"]["arm"]["reach_m"].get<double>(), 0.8);
}

TEST(Cli, PlantSimulateWritesTheCsvLogAndReport) {
  const auto dir = tempDir("plant_step");
  const Result r = runFullarm("plant simulate --joint EB --input step --duration 0.2 --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream csv(dir / "plant_log.csv");
  std::string header;
  std::getline(csv, header);
  EXPECT_EQ(header, "time_s,command_v,q_rad,qd_rad_s,tau_measured_nm,p_a_pa,p_b_pa,spool_fraction");
  int rows = 0;
  for (std::string line; std::getline(csv, line);) ++rows;
  EXPECT_GE(rows, 200);  // 0.2 s at 1 kHz
  EXPECT_TRUE(std::filesystem::exists(dir / "report.html"));
}

TEST(Cli, PlantSimulateRejectsAnUnknownJoint) {
  const Result r =
      runFullarm("plant simulate --joint ELBOW --duration 0.1 --out " + tempDir("plant_bad_joint").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("ELBOW"), std::string::npos) << r.output;
}

TEST(Cli, PlantSimulateRejectsAMalformedCsv) {
  const auto dir = tempDir("plant_bad_csv");
  const auto csv = dir / "input.csv";
  std::ofstream(csv) << "time_s,command\n0.0,0.1\n0.001,abc\n";
  const Result r = runFullarm("plant simulate --joint EB --input " + csv.string() + " --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find(csv.string()), std::string::npos) << r.output;
}

// `fullarm validate`: the verdict is the exit code (0 pass, 1 fail) and summary.json names each
// joint's result; bad input is exit 2 with the file and key path.
TEST(Cli, ValidateWritesAVerdictPerJoint) {
  const auto dir = tempDir("validate");
  const Result r = runFullarm("validate --joints EB --samples 3 --out " + dir.string());
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  std::ifstream in(dir / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(in);
  EXPECT_EQ(summary["subcommand"], "validate");
  const nlohmann::json& v = summary["results"]["validate"];
  ASSERT_EQ(v["joints"].size(), 1u);
  EXPECT_EQ(v["joints"][0]["name"], "R_EB");
  EXPECT_EQ(v["joints"][0]["monte_carlo"]["samples"], 3);
  EXPECT_EQ(v["pass"].get<bool>(), r.exit_code == 0);
  EXPECT_TRUE(std::filesystem::exists(dir / "report.html"));
}

TEST(Cli, ValidateRejectsBadGains) {
  const auto dir = tempDir("validate_bad");
  std::ifstream in(source("config/dts_gains.yaml"));
  std::stringstream text;
  text << in.rdbuf();
  std::string yaml = text.str();
  // Negate the first joint's model inertia, whatever value the tuner wrote.
  const std::string key = "inertia_kgm2: ";
  const auto at = yaml.find(key);
  ASSERT_NE(at, std::string::npos) << "config/dts_gains.yaml has no " << key;
  const auto value_at = at + key.size();
  yaml = yaml.substr(0, value_at) + "-" + yaml.substr(value_at);
  const auto gains = dir / "gains.yaml";
  std::ofstream(gains) << yaml;
  Result r = runFullarm("validate --gains " + gains.string() + " --samples 1 --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("impedance.inertia_kgm2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(gains.string()), std::string::npos) << r.output;
  r = runFullarm("validate --joints ELBOW --samples 1 --out " + (dir / "out").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("ELBOW"), std::string::npos) << r.output;
}

}  // namespace
