// The static-hold log and the pairing of the two sides: a strict parser whose errors name the
// line, sides averaged per posture, device angles scattered into a configuration.

#include "fullarm/identification/static_holds.hpp"

#include <gtest/gtest.h>

#include <string>

#include "fullarm/identification/signal_csv.hpp"

namespace fullarm::identification {
namespace {

const std::vector<std::string> kJoints{"A", "B"};
const std::string kHeader = "time_s,posture_index,side_sign,q_A_rad,q_B_rad,tau_A_nm,tau_B_nm\n";

/// The line number a parse error reports (0 when it does not throw CsvFormatError).
std::size_t errorLine(const std::string& text, std::string* message = nullptr) {
  try {
    (void)parseStaticHoldsCsv(text, "holds.csv", kJoints);
  } catch (const CsvFormatError& e) {
    if (message != nullptr) *message = e.what();
    return e.line();
  }
  return 0;
}

TEST(StaticHoldsTest, ParsesALogAndAveragesTheTwoSidesOfEachPosture) {
  const std::string text = kHeader +
                           "1.0,0,1,0.11,0.21,2.0,-1.0\n"
                           "2.0,0,-1,0.09,0.19,1.0,-2.0\n"
                           "3.0,1,-1,0.5,0.6,4.0,5.0\n"
                           "4.0,1,1,0.7,0.8,6.0,7.0\n";
  const auto holds = parseStaticHoldsCsv(text, "holds.csv", kJoints);
  ASSERT_EQ(holds.size(), 4u);
  EXPECT_EQ(holds[1].side, -1);
  EXPECT_EQ(holds[2].posture_index, 1);
  const auto combined = combineSides(holds);
  ASSERT_EQ(combined.size(), 2u);
  EXPECT_NEAR(combined[0].q_rad[0], 0.10, 1e-15);
  EXPECT_NEAR(combined[0].q_rad[1], 0.20, 1e-15);
  EXPECT_NEAR(combined[0].tau_nm[0], 1.5, 1e-15);  // friction +-0.5 N m cancelled
  EXPECT_NEAR(combined[0].tau_nm[1], -1.5, 1e-15);
  EXPECT_NEAR(combined[1].tau_nm[1], 6.0, 1e-15);
}

TEST(StaticHoldsTest, AMalformedLogIsAnErrorNamingTheLine) {
  std::string message;
  EXPECT_EQ(errorLine(kHeader + "1.0,0,1,0.1,0.2,1.0,2.0\n2.0,0,0,0.1,0.2,1.0,2.0\n", &message), 3u);
  EXPECT_NE(message.find("side_sign"), std::string::npos) << message;
  EXPECT_EQ(errorLine(kHeader + "1.0,0.5,1,0.1,0.2,1.0,2.0\n", &message), 2u);
  EXPECT_NE(message.find("posture_index"), std::string::npos) << message;
  EXPECT_EQ(errorLine(kHeader + "1.0,-1,1,0.1,0.2,1.0,2.0\n"), 2u);
  EXPECT_EQ(errorLine(kHeader + "1.0,0,1,0.1,nan,1.0,2.0\n"), 2u);
  EXPECT_EQ(errorLine(kHeader + "1.0,0,1,0.1,0.2,1.0,2.0\n1.0,0,-1,0.1,0.2,1.0,2.0\n"), 3u);  // time not increasing
  EXPECT_EQ(errorLine(kHeader + "1.0,0,1,0.1,0.2,1.0\n"), 2u);                                // short row
  EXPECT_EQ(errorLine("time_s,posture_index,side_sign,q_A_deg,q_B_rad,tau_A_nm,tau_B_nm\n1,0,1,0,0,0,0\n", &message),
            1u);  // wrong unit
  EXPECT_NE(message.find("q_A_deg"), std::string::npos) << message;
  EXPECT_EQ(errorLine("time_s,posture_index,side_sign,q_A_rad,tau_A_nm,tau_B_nm\n1,0,1,0,0,0\n", &message), 1u);
  EXPECT_NE(message.find("q_B_rad"), std::string::npos) << message;  // missing column
  EXPECT_EQ(errorLine(""), 1u);                                      // empty file
}

TEST(StaticHoldsTest, APostureHeldFromOneSideOnlyIsRefused) {
  StaticHold above{0, 1, 1.0, Eigen::VectorXd::Zero(2), Eigen::VectorXd::Zero(2)};
  StaticHold below{0, -1, 2.0, Eigen::VectorXd::Zero(2), Eigen::VectorXd::Zero(2)};
  StaticHold lone{3, 1, 3.0, Eigen::VectorXd::Zero(2), Eigen::VectorXd::Zero(2)};
  EXPECT_NO_THROW((void)combineSides({above, below}));
  try {
    (void)combineSides({above, below, lone});
    ADD_FAILURE() << "a posture held from one side was accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("posture 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)combineSides({above, above, below}), std::invalid_argument);
}

TEST(StaticHoldsTest, HoldConfigurationScattersTheDeviceAnglesIntoTheBase) {
  const arm::JointSelection joints(4, {2, 0});
  const Eigen::VectorXd base = Eigen::Vector4d(1.0, 2.0, 3.0, 4.0);
  const Eigen::VectorXd q = holdConfiguration(base, joints, Eigen::Vector2d(-3.0, -1.0));
  EXPECT_EQ(q, Eigen::Vector4d(-1.0, 2.0, -3.0, 4.0));
  EXPECT_THROW((void)holdConfiguration(base, joints, Eigen::Vector3d::Zero()), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::identification
