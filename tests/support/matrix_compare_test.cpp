#include "matrix_compare.hpp"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace fullarm::testing {
namespace {

TEST(MatricesNear, AcceptsWithinTolerance) {
  Eigen::Matrix2d a;
  a << 1, 2, 3, 4;
  Eigen::Matrix2d b = a;
  b(1, 0) += 0.5e-9;
  EXPECT_TRUE(matricesNear(a, b, 1e-9));
}

TEST(MatricesNear, RejectsAndReportsTheWorstEntry) {
  Eigen::Matrix2d a = Eigen::Matrix2d::Zero();
  Eigen::Matrix2d b = a;
  b(1, 0) = 2e-3;
  const ::testing::AssertionResult r = matricesNear(a, b, 1e-6);
  EXPECT_FALSE(r);
  EXPECT_NE(std::string(r.message()).find("at (1, 0)"), std::string::npos) << r.message();
  EXPECT_NE(std::string(r.message()).find("0.002"), std::string::npos) << r.message();
}

TEST(MatricesNear, RejectsSizeMismatch) {
  EXPECT_FALSE(matricesNear(Eigen::Vector3d::Zero(), Eigen::Vector2d::Zero(), 1.0));
}

TEST(MatricesNear, RejectsNonFinite) {
  Eigen::Vector2d a(1.0, std::numeric_limits<double>::quiet_NaN());
  EXPECT_FALSE(matricesNear(a, a, 1.0));
}

TEST(MatricesNear, MacroFailsTheTest) {
  EXPECT_NONFATAL_FAILURE(EXPECT_MATRIX_NEAR(Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 1), 0.5), "max |A - B|");
}

}  // namespace
}  // namespace fullarm::testing
