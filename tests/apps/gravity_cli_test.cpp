// `fullarm gravity` end to end: the fit to the reference writes an arm YAML that loads and
// whose gravity is the reference's at a published posture; a holds log is fitted (the written
// arm's gravity against the logged torques, and the residual the command reports); a malformed
// log exits 2 naming the line; the random postures' options are refused beside a log.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "cli_runner.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/identification/reference_gravity.hpp"

namespace {

using Result = fullarm::test::CliResult;
using fullarm::test::runFullarm;
namespace id = fullarm::identification;

std::filesystem::path tempDir(const std::string& name) {
  return fullarm::test::cliTempDir("fullarm_gravity_cli_test", name);
}

TEST(GravityCli, FitToTheReferenceWritesAnArmYamlWithTheReferencesGravity) {
  const auto dir = tempDir("reference");
  const Result r = runFullarm("gravity --postures 60 --quiet --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("R_EB"), std::string::npos) << r.output;
  ASSERT_TRUE(std::filesystem::exists(dir / "gravity.csv"));
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(dir / "arm.yaml");
  fullarm::arm::ArmData data(model);
  const id::PublishedGravity home = id::publishedGravity()[1];
  Eigen::VectorXd q = model.defaultPosture();
  for (int k = 0; k < 7; ++k) q[k] = home.q_rad[static_cast<std::size_t>(k)];
  fullarm::arm::computeGravityTorques(model, data, q);
  for (int k = 0; k < 7; ++k) {
    // The YAML's 10 significant digits and the published six decimals.
    EXPECT_NEAR(data.tau_gravity[k], home.tau_nm[static_cast<std::size_t>(k)], 1e-5) << "joint " << k;
  }
}

TEST(GravityCli, HoldsLogIsFittedAndAMalformedOneNamesTheLine) {
  const auto dir = tempDir("holds");
  const std::string header =
      "time_s,posture_index,side_sign,q_R_SFE_rad,q_R_SAA_rad,q_R_HR_rad,q_R_EB_rad,q_R_WR_rad,q_R_WFE_rad,"
      "q_R_WAA_rad,tau_R_SFE_nm,tau_R_SAA_nm,tau_R_HR_nm,tau_R_EB_nm,tau_R_WR_nm,tau_R_WFE_nm,tau_R_WAA_nm\n";
  // Holds whose torques are the reference's own gravity at the published postures (both sides).
  std::ostringstream rows;
  rows.precision(17);
  double t = 1.0;
  int index = 0;
  for (const auto& hold : id::publishedGravity()) {
    for (const int side : {1, -1}) {
      rows << t << ',' << index << ',' << side;
      for (double v : hold.q_rad) rows << ',' << v;
      for (double v : hold.tau_nm) rows << ',' << v;
      rows << '\n';
      t += 1.0;
    }
    ++index;
  }
  { std::ofstream(dir / "holds.csv") << header << rows.str(); }
  const Result ok =
      runFullarm("gravity --holds " + (dir / "holds.csv").string() + " --quiet --out " + (dir / "out").string());
  ASSERT_EQ(ok.exit_code, 0) << ok.output;
  // The written arm's gravity at the three postures, against the logged torques: the RMS per
  // joint is the residual gravity.csv reports (to the YAML's and the CSV's digits), and small
  // against the torques themselves (a fit to 3 postures x 7 joints of the reference's own load).
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(dir / "out" / "arm.yaml");
  fullarm::arm::ArmData data(model);
  Eigen::VectorXd squared = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd torque_squared = Eigen::VectorXd::Zero(7);
  for (const auto& hold : id::publishedGravity()) {
    Eigen::VectorXd q = model.defaultPosture();
    for (int k = 0; k < 7; ++k) q[k] = hold.q_rad[static_cast<std::size_t>(k)];
    fullarm::arm::computeGravityTorques(model, data, q);
    for (int k = 0; k < 7; ++k) {
      const double logged = hold.tau_nm[static_cast<std::size_t>(k)];
      squared[k] += (data.tau_gravity[k] - logged) * (data.tau_gravity[k] - logged);
      torque_squared[k] += logged * logged;
    }
  }
  std::ifstream csv(dir / "out" / "gravity.csv");
  std::string line;
  ASSERT_TRUE(std::getline(csv, line));
  EXPECT_EQ(line, "joint,residual_rms_nm");
  for (int k = 0; k < 7; ++k) {
    ASSERT_TRUE(std::getline(csv, line)) << "joint " << k;
    const double reported = std::stod(line.substr(line.find(',') + 1));
    const double rms = std::sqrt(squared[k] / 3.0);
    EXPECT_NEAR(rms, reported, 1e-5 + 1e-4 * reported) << line;
    EXPECT_LT(rms, 0.01 * std::sqrt(torque_squared[k] / 3.0)) << line;
  }
  { std::ofstream(dir / "bad.csv") << header << rows.str() << "99.0,3,2,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n"; }
  const Result bad =
      runFullarm("gravity --holds " + (dir / "bad.csv").string() + " --quiet --out " + (dir / "out2").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("bad.csv:8"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("side_sign"), std::string::npos) << bad.output;
  for (const char* option : {"--postures 40", "--seed 3"}) {
    const Result both = runFullarm("gravity --holds " + (dir / "holds.csv").string() + " " + option +
                                   " --quiet --out " + (dir / "out3").string());
    EXPECT_EQ(both.exit_code, 2) << option << "\n" << both.output;
    EXPECT_NE(both.output.find(std::string(option).substr(0, std::string(option).find(' '))), std::string::npos)
        << both.output;
  }
}

}  // namespace
