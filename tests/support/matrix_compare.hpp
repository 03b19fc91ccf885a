#pragma once
/// @file
/// Matrix comparison for GoogleTest that prints the residuals, plus named tolerances.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <sstream>
#include <string>

namespace fullarm::testing {

/// Named tolerances used across the suites. Each says what it is for.
struct Tolerance {
  /// Two independent computations of the same double-precision quantity (KDL vs fullarm).
  static constexpr double kExact = 1e-9;
  /// Central finite differences with step kFdStep on smooth functions of O(1) size.
  static constexpr double kFiniteDifference = 1e-6;
  /// Step of the central finite differences.
  static constexpr double kFdStep = 1e-6;
  /// Published figures printed to six decimals (docs/dts-reference.md).
  static constexpr double kSixDecimals = 1.5e-6;
};

/// Succeeds when max |a - b| <= tol; on failure prints both matrices, the residual and where
/// the largest entry is.
template <typename A, typename B>
::testing::AssertionResult matricesNear(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b, double tol) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) {
    return ::testing::AssertionFailure() << "size mismatch: " << a.rows() << "x" << a.cols() << " vs " << b.rows()
                                         << "x" << b.cols();
  }
  const Eigen::MatrixXd diff = Eigen::MatrixXd(a.template cast<double>()) - Eigen::MatrixXd(b.template cast<double>());
  if (!diff.allFinite()) {
    return ::testing::AssertionFailure() << "non-finite entries\nA =\n" << a << "\nB =\n" << b;
  }
  Eigen::Index r = 0;
  Eigen::Index c = 0;
  const double worst = diff.size() == 0 ? 0.0 : diff.cwiseAbs().maxCoeff(&r, &c);
  if (worst <= tol) return ::testing::AssertionSuccess();
  std::ostringstream s;
  s.precision(12);
  s << "max |A - B| = " << worst << " at (" << r << ", " << c << ") > tolerance " << tol << "\nA =\n"
    << a << "\nB =\n"
    << b << "\nA - B =\n"
    << diff;
  return ::testing::AssertionFailure() << s.str();
}

}  // namespace fullarm::testing

#define EXPECT_MATRIX_NEAR(a, b, tol) EXPECT_TRUE(::fullarm::testing::matricesNear((a), (b), (tol)))
#define ASSERT_MATRIX_NEAR(a, b, tol) ASSERT_TRUE(::fullarm::testing::matricesNear((a), (b), (tol)))
