// `fullarm gravity` end to end: the fit to the reference writes an arm YAML that loads and
// whose gravity is the reference's at a published posture; a holds log is fitted; a malformed
// log exits 2 naming the line.

#include <gtest/gtest.h>

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
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "arm.yaml"));
  { std::ofstream(dir / "bad.csv") << header << rows.str() << "99.0,3,2,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n"; }
  const Result bad =
      runFullarm("gravity --holds " + (dir / "bad.csv").string() + " --quiet --out " + (dir / "out2").string());
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("bad.csv:8"), std::string::npos) << bad.output;
  EXPECT_NE(bad.output.find("side_sign"), std::string::npos) << bad.output;
}

}  // namespace
