// Rodas3 against closed-form solutions (convergence order 3 at fixed steps, tolerance-
// proportional error when adaptive) and Eigen's matrix exponential (a stiff linear system), and
// its block elimination against its dense LU.

#include <gtest/gtest.h>

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <unsupported/Eigen/MatrixFunctions>

#include "fullarm/plant/rosenbrock.hpp"
#include "rosenbrock_test_system.hpp"

namespace fullarm::plant {
namespace {

using test::fixedStepError;
using test::NonStiff;
using test::nonStiffExact;

TEST(Rodas3, ConvergesWithOrderThree) {
  const double e1 = fixedStepError(0.1);
  const double e2 = fixedStepError(0.05);
  const double e3 = fixedStepError(0.025);
  const double order1 = std::log2(e1 / e2);
  const double order2 = std::log2(e2 / e3);
  EXPECT_NEAR(order1, 3.0, 0.3);
  EXPECT_NEAR(order2, 3.0, 0.3);
}

// Rodas4 (Hairer & Wanner's RODAS, order 4): halving the fixed step divides the error by 2^4.
// (A wrong coefficient in the sixth digit already breaks this: the order conditions are exact.)
TEST(Rodas4, ConvergesWithOrderFour) {
  const double e1 = fixedStepError(0.2, RosenbrockMethod::kRodas4);
  const double e2 = fixedStepError(0.1, RosenbrockMethod::kRodas4);
  const double e3 = fixedStepError(0.05, RosenbrockMethod::kRodas4);
  const double order1 = std::log2(e1 / e2);
  const double order2 = std::log2(e2 / e3);
  EXPECT_NEAR(order1, 4.0, 0.3);
  EXPECT_NEAR(order2, 4.0, 0.3);
  EXPECT_LT(e3, 0.1 * fixedStepError(0.05));  // and it beats Rodas3 at the same step
}

// Failures come back as the one real-time status: a spent step budget and a non-finite
// right-hand side, each with its code and fault bit, and the state is left where it was.
struct NonFiniteRhs {
  static void rhs(void* /*user*/, const double* /*y*/, double* f) noexcept {
    f[0] = std::numeric_limits<double>::quiet_NaN();
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    j[0] = 0.0;
  }
};

TEST(Rosenbrock, FailuresReportTheirCauseAsRtStatus) {
  RosenbrockIntegrator r;
  const double atol[3] = {1e-10, 1e-10, 1e-10};
  r.configure(3, atol, 1e-10, 3, {&NonStiff::rhs, &NonStiff::jacobian, nullptr});
  r.resetStepSize(1e-3);
  Eigen::Vector3d y(0.1, 0.0, 1.0);
  const core::RtStatus budget = r.advance(y.data(), 1.0);  // needs far more than 3 steps
  EXPECT_EQ(budget.code, core::RtCode::kSolverFailure);
  EXPECT_EQ(budget.faults, core::kFaultTooManySteps);
  EXPECT_EQ(y, Eigen::Vector3d(0.1, 0.0, 1.0));

  RosenbrockIntegrator bad;
  const double atol1[1] = {1e-6};
  bad.configure(1, atol1, 1e-6, 100, {&NonFiniteRhs::rhs, &NonFiniteRhs::jacobian, nullptr});
  double y1 = 1.0;
  const core::RtStatus nan = bad.advance(&y1, 0.1);
  EXPECT_EQ(nan.code, core::RtCode::kBadState);
  EXPECT_EQ(nan.faults, core::kFaultNonFiniteState);
  EXPECT_EQ(y1, 1.0);
}

// Both schemes against the closed form at three tolerances; the right-hand sides per attempt are
// the scheme's new stage evaluations (Rodas3 2, Rodas4 5) besides the one inside the Jacobian pass.
TEST(Rosenbrock, AdaptiveErrorFollowsTheTolerance) {
  for (const RosenbrockMethod method : {RosenbrockMethod::kRodas3, RosenbrockMethod::kRodas4}) {
    SCOPED_TRACE(method == RosenbrockMethod::kRodas3 ? "Rodas3" : "Rodas4");
    const long stage_rhs = method == RosenbrockMethod::kRodas3 ? 2 : 5;
    for (const double rtol : {1e-4, 1e-6, 1e-8}) {
      RosenbrockIntegrator r;
      r.setMethod(method);
      const double atol[3] = {rtol, rtol, rtol};
      r.configure(3, atol, rtol, 100000, {&NonStiff::rhs, &NonStiff::jacobian, nullptr});
      Eigen::Vector3d y(0.1, 0.0, 1.0);
      for (int k = 0; k < 20; ++k) ASSERT_TRUE(r.advance(y.data(), 0.1).ok());
      const double err = (y - nonStiffExact(2.0)).cwiseAbs().maxCoeff();
      EXPECT_LT(err, 100.0 * rtol) << "rtol " << rtol;
      EXPECT_GT(r.stats().steps, 20);
      EXPECT_EQ(r.stats().rhs_evals, r.stats().jac_evals + stage_rhs * (r.stats().steps + r.stats().rejected));
    }
  }
}

// Stiff linear system y' = A (y - g) with eigenvalues -1e6 and -1, exact y = g + expm(A t)(y0 - g),
// stepped at h = 1 ms (h |lambda| = 1000): L-stability damps the fast mode.
struct Stiff {
  Eigen::Matrix2d a;
  Eigen::Vector2d g;
  static void rhs(void* user, const double* y, double* f) noexcept {
    const auto* s = static_cast<const Stiff*>(user);
    Eigen::Map<Eigen::Vector2d> out(f);
    out = s->a * (Eigen::Map<const Eigen::Vector2d>(y) - s->g);
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    Eigen::Map<Eigen::Matrix2d> J(j);
    J = static_cast<const Stiff*>(user)->a;
  }
};

TEST(Rodas3, StiffLinearSystemMatchesMatrixExponential) {
  for (const RosenbrockMethod method :
       {RosenbrockMethod::kRodas3, RosenbrockMethod::kRodas4, RosenbrockMethod::kRos34pw2}) {
    SCOPED_TRACE(method == RosenbrockMethod::kRodas3   ? "Rodas3"
                 : method == RosenbrockMethod::kRodas4 ? "Rodas4"
                                                       : "ROS34PW2");
    Stiff s;
    Eigen::Matrix2d v;
    v << 1.0, 1.0, 0.5, -1.0;
    s.a = v * Eigen::Vector2d(-1e6, -1.0).asDiagonal() * v.inverse();
    s.g = Eigen::Vector2d(2.0, -1.0);
    RosenbrockIntegrator r;
    r.setMethod(method);
    const double atol[2] = {1e-9, 1e-9};
    r.configure(2, atol, 1e-7, 1000, {&Stiff::rhs, &Stiff::jacobian, &s});
    const Eigen::Vector2d y0(0.0, 0.0);
    Eigen::Vector2d y = y0;
    for (int k = 0; k < 1000; ++k) ASSERT_TRUE(r.advance(y.data(), 1e-3).ok());
    const Eigen::Vector2d exact = s.g + Eigen::MatrixXd(s.a * 1.0).exp() * (y0 - s.g);
    EXPECT_LT((y - exact).cwiseAbs().maxCoeff(), 1e-5);
    EXPECT_LT(r.stats().steps, 3000);  // not limited by the fast mode
  }
}

// y' = A (y - g) of size N with eigenvalues from -1e5 to -1 and eigenvectors that make partial
// pivoting swap rows of G = I / (h gamma) - A: exercises the dense LU at every size the plant
// dispatches on (4, 6 and 7 at compile time, 5 at run time), against Eigen's matrix exponential.
template <int N>
struct StiffN {
  Eigen::Matrix<double, N, N> a;
  Eigen::Matrix<double, N, 1> g;
  static void rhs(void* user, const double* y, double* f) noexcept {
    const auto* s = static_cast<const StiffN*>(user);
    Eigen::Map<Eigen::Matrix<double, N, 1>> out(f);
    out = s->a * (Eigen::Map<const Eigen::Matrix<double, N, 1>>(y) - s->g);
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    Eigen::Map<Eigen::Matrix<double, N, N>> jac(j);
    jac = static_cast<const StiffN*>(user)->a;
  }
};

template <int N>
void expectStiffSystemMatchesMatrixExponential() {
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;
  StiffN<N> s;
  Vector lambda;
  for (int i = 0; i < N; ++i) lambda[i] = -std::pow(10.0, 5.0 * i / (N - 1));
  s.g = Vector::LinSpaced(N, 1.0, -1.0);
  // Dense, well-mixed eigenvectors, from the first seed whose G = I / (h gamma) - A (at h = 1 ms)
  // makes partial pivoting swap rows: the test means something only if the LU pivots.
  for (int seed = 1;; ++seed) {
    ASSERT_LT(seed, 100) << "N = " << N;
    std::srand(static_cast<unsigned>(seed));
    const Matrix v = Matrix::Random() + 0.5 * Matrix::Identity().rowwise().reverse();
    s.a = v * lambda.asDiagonal() * v.inverse();
    const Eigen::PartialPivLU<Matrix> lu(Matrix::Identity() / (1e-3 * 0.5) - s.a);
    if ((lu.permutationP().indices().array() != Eigen::Array<int, N, 1>::LinSpaced(N, 0, N - 1)).any()) break;
  }
  std::array<double, N> atol{};
  atol.fill(1e-9);
  RosenbrockIntegrator r;
  r.configure(N, atol.data(), 1e-7, 10000, {&StiffN<N>::rhs, &StiffN<N>::jacobian, &s});
  const Vector y0 = Vector::Zero();
  Vector y = y0;
  for (int k = 0; k < 200; ++k) ASSERT_TRUE(r.advance(y.data(), 1e-3).ok());
  // The exponential of a dynamic-size copy: one instantiation of it serves every N.
  const Vector exact = s.g + Eigen::MatrixXd(s.a * 0.2).exp() * (y0 - s.g);
  EXPECT_LT((y - exact).cwiseAbs().maxCoeff(), 1e-5) << "N = " << N;
  EXPECT_GT((exact - s.g).cwiseAbs().maxCoeff(), 1e-2);  // the slow modes have not decayed
  // A wrong solve is rescued by the error control at tiny steps, where G is nearly diagonal, so
  // the step count is the check (1,000-1,300 steps, <= 17 rejections with a correct LU; with the
  // permutation dropped from the 6 x 6 solve, 3,521 steps and 1,165 rejections).
  EXPECT_LT(r.stats().steps, 2000) << "N = " << N;
  EXPECT_LT(r.stats().rejected, 100) << "N = " << N;
}

TEST(Rodas3, StiffSystemsOfEveryLuSizeMatchMatrixExponential) {
  expectStiffSystemMatchesMatrixExponential<4>();
  expectStiffSystemMatchesMatrixExponential<5>();
  expectStiffSystemMatchesMatrixExponential<6>();
  expectStiffSystemMatchesMatrixExponential<7>();
}

// Two 4-state blocks coupled only through a 2-state border: block elimination = dense LU.
struct Bordered {
  Eigen::Matrix<double, 10, 10> a;
  static void rhs(void* user, const double* y, double* f) noexcept {
    const auto* s = static_cast<const Bordered*>(user);
    const Eigen::Map<const Eigen::Matrix<double, 10, 1>> x(y);
    Eigen::Map<Eigen::Matrix<double, 10, 1>> out(f);
    out = s->a * x;
    out += 0.1 * x.array().square().matrix();  // mildly nonlinear, Jacobian diagonal 0.2 x
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    Eigen::Map<Eigen::Matrix<double, 10, 10>> J(j);
    J = static_cast<const Bordered*>(user)->a;
    for (int i = 0; i < 10; ++i) J(i, i) += 0.2 * y[i];
  }
};

// Integrates system `s` (a member matrix `a` of size N x N, two 4-state blocks then the border)
// 50 steps of 10 ms with a dense Rodas3 and with one told its block structure: same steps and
// the same state to 1e-12 relative.
template <class System>
// `rejected` (if given) receives the block integrators' rejected steps over the three methods (a
// rejection refactorises with the same Jacobian and so reuses the block structure found with it).
void expectBlockEliminationMatchesDense(System& s, bool expect_halved_border, long* rejected = nullptr) {
  for (const RosenbrockMethod method :
       {RosenbrockMethod::kRodas3, RosenbrockMethod::kRodas4, RosenbrockMethod::kRos34pw2}) {
    SCOPED_TRACE(method == RosenbrockMethod::kRodas3   ? "Rodas3"
                 : method == RosenbrockMethod::kRodas4 ? "Rodas4"
                                                       : "ROS34PW2");
    constexpr int kN = decltype(System::a)::RowsAtCompileTime;
    using Vector = Eigen::Matrix<double, kN, 1>;
    std::array<double, kN> atol{};
    atol.fill(1e-8);
    RosenbrockIntegrator dense;
    RosenbrockIntegrator blocks;
    dense.setMethod(method);
    blocks.setMethod(method);
    dense.configure(kN, atol.data(), 1e-6, 10000, {&System::rhs, &System::jacobian, &s});
    blocks.configure(kN, atol.data(), 1e-6, 10000, {&System::rhs, &System::jacobian, &s});
    blocks.setBlockStructure(2);
    Vector yd = Vector::LinSpaced(kN, -0.5, 0.5);
    Vector yb = yd;
    for (int k = 0; k < 50; ++k) {
      ASSERT_TRUE(dense.advance(yd.data(), 1e-2).ok());
      ASSERT_TRUE(blocks.advance(yb.data(), 1e-2).ok());
    }
    EXPECT_EQ(dense.stats().steps, blocks.stats().steps);
    EXPECT_LT((yd - yb).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, yd.cwiseAbs().maxCoeff()));
    EXPECT_GT(yd.cwiseAbs().maxCoeff(), 1e-3);  // not decayed to nothing
    EXPECT_EQ(blocks.halvedBorder(), expect_halved_border);
    if (rejected != nullptr) *rejected += blocks.stats().rejected;
  }
}

TEST(Rodas3, BlockEliminationMatchesDenseLu) {
  Bordered s;
  s.a.setZero();
  std::srand(5);
  const Eigen::Matrix4d b0 = Eigen::Matrix4d::Random();
  const Eigen::Matrix4d b1 = Eigen::Matrix4d::Random();
  s.a.block<4, 4>(0, 0) = b0 - 6.0 * Eigen::Matrix4d::Identity();
  s.a.block<4, 4>(4, 4) = b1 - 300.0 * Eigen::Matrix4d::Identity();
  s.a.block<4, 2>(0, 8) = Eigen::Matrix<double, 4, 2>::Random();
  s.a.block<4, 2>(4, 8) = Eigen::Matrix<double, 4, 2>::Random();
  s.a.block<2, 8>(8, 0) = Eigen::Matrix<double, 2, 8>::Random();
  s.a.block<2, 2>(8, 8) = -Eigen::Matrix2d::Identity();
  expectBlockEliminationMatchesDense(s, /*expect_halved_border=*/false);  // this border is not [x; v]
}

// Two 4-state blocks and a second-order border [x1 x2 v1 v2] with x' = v exactly, as the
// plant's joint angles and velocities: the half-size Schur system gives the dense-LU solution.
struct SecondOrderBordered {
  Eigen::Matrix<double, 12, 12> a;
  static void rhs(void* user, const double* y, double* f) noexcept {
    const auto* s = static_cast<const SecondOrderBordered*>(user);
    const Eigen::Map<const Eigen::Matrix<double, 12, 1>> x(y);
    Eigen::Map<Eigen::Matrix<double, 12, 1>> out(f);
    out = s->a * x;
    // mildly nonlinear in every state but the positions (whose rows must stay x' = v)
    for (int i = 0; i < 12; ++i) {
      if (i != 8 && i != 9) out[i] += 0.1 * x[i] * x[i];
    }
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    Eigen::Map<Eigen::Matrix<double, 12, 12>> J(j);
    J = static_cast<const SecondOrderBordered*>(user)->a;
    for (int i = 0; i < 12; ++i) {
      if (i != 8 && i != 9) J(i, i) += 0.2 * y[i];
    }
  }
};

TEST(Rodas3, BlockEliminationWithSecondOrderBorderMatchesDenseLu) {
  SecondOrderBordered s;
  s.a.setZero();
  std::srand(7);
  s.a.block<4, 4>(0, 0) = Eigen::Matrix4d::Random() - 8.0 * Eigen::Matrix4d::Identity();
  s.a.block<4, 4>(4, 4) = Eigen::Matrix4d::Random() - 500.0 * Eigen::Matrix4d::Identity();
  s.a.block<4, 2>(0, 8) = Eigen::Matrix<double, 4, 2>::Random();   // blocks see x
  s.a.block<4, 2>(4, 10) = Eigen::Matrix<double, 4, 2>::Random();  // and v
  s.a.block<2, 8>(10, 0) = Eigen::Matrix<double, 2, 8>::Random();  // v' sees both blocks
  s.a.block<2, 2>(10, 8) = -4.0 * Eigen::Matrix2d::Identity();     // springs
  s.a.block<2, 2>(10, 10) = -0.5 * Eigen::Matrix2d::Identity();    // dampers
  s.a.block<2, 2>(8, 10) = Eigen::Matrix2d::Identity();            // x' = v
  expectBlockEliminationMatchesDense(s, /*expect_halved_border=*/true);
}

// The plant's shape: two 4-state blocks and a second-order border of 7 positions and 7
// velocities, so the halved Schur system is 7 x 7 (the compile-time-size LU).
struct SevenJointBordered {
  Eigen::Matrix<double, 22, 22> a;
  static void rhs(void* user, const double* y, double* f) noexcept {
    const auto* s = static_cast<const SevenJointBordered*>(user);
    const Eigen::Map<const Eigen::Matrix<double, 22, 1>> x(y);
    Eigen::Map<Eigen::Matrix<double, 22, 1>> out(f);
    out = s->a * x;
    for (int i = 0; i < 22; ++i) {
      if (i < 8 || i >= 15) out[i] += 0.1 * x[i] * x[i];
    }
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    Eigen::Map<Eigen::Matrix<double, 22, 22>> J(j);
    J = static_cast<const SevenJointBordered*>(user)->a;
    for (int i = 0; i < 22; ++i) {
      if (i < 8 || i >= 15) J(i, i) += 0.2 * y[i];
    }
  }
};

TEST(Rodas3, BlockEliminationWithSevenJointBorderMatchesDenseLu) {
  SevenJointBordered s;
  s.a.setZero();
  std::srand(13);
  using Matrix7 = Eigen::Matrix<double, 7, 7>;
  s.a.block<4, 4>(0, 0) = Eigen::Matrix4d::Random() - 8.0 * Eigen::Matrix4d::Identity();
  s.a.block<4, 4>(4, 4) = Eigen::Matrix4d::Random() - 500.0 * Eigen::Matrix4d::Identity();
  s.a.block<4, 7>(0, 8) = Eigen::Matrix<double, 4, 7>::Random();                   // blocks see x
  s.a.block<4, 7>(4, 15) = Eigen::Matrix<double, 4, 7>::Random();                  // and v
  s.a.block<7, 8>(15, 0) = Eigen::Matrix<double, 7, 8>::Random();                  // v' sees both blocks
  s.a.block<7, 7>(15, 8) = -4.0 * Matrix7::Identity() + 0.5 * Matrix7::Random();   // coupled springs
  s.a.block<7, 7>(15, 15) = -0.5 * Matrix7::Identity() + 0.1 * Matrix7::Random();  // and dampers
  s.a.block<7, 7>(8, 15) = Matrix7::Identity();                                    // x' = v
  expectBlockEliminationMatchesDense(s, /*expect_halved_border=*/true);
}

// The seven-joint shape with a border whose dependence on the first block's states switches on and
// off: v' gets g_ic max(x_c, 0)^2 from block state c, so the Jacobian's border entries in those
// columns are exact zeros while x_c <= 0 and nonzero otherwise. The block elimination skips the
// border columns that are exact zeros, found once per Jacobian; a pattern kept from an earlier
// Jacobian would drop live entries and leave the dense-LU solution.
struct GatedBordered {
  Eigen::Matrix<double, 22, 22> a;
  Eigen::Matrix<double, 7, 4> g;
  int zero_columns = 0;  // block-0 columns seen as exact zeros / nonzero by the Jacobian calls
  int live_columns = 0;
  static void rhs(void* user, const double* y, double* f) noexcept {
    const auto* s = static_cast<const GatedBordered*>(user);
    const Eigen::Map<const Eigen::Matrix<double, 22, 1>> x(y);
    Eigen::Map<Eigen::Matrix<double, 22, 1>> out(f);
    out = s->a * x;
    for (int i = 0; i < 22; ++i) {
      if (i < 8 || i >= 15) out[i] += 0.1 * x[i] * x[i];
    }
    for (int c = 0; c < 4; ++c) {
      const double on = std::max(x[c], 0.0);
      for (int i = 0; i < 7; ++i) out[15 + i] += s->g(i, c) * on * on;
    }
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    auto* s = static_cast<GatedBordered*>(user);
    Eigen::Map<Eigen::Matrix<double, 22, 22>> J(j);
    J = s->a;
    for (int i = 0; i < 22; ++i) {
      if (i < 8 || i >= 15) J(i, i) += 0.2 * y[i];
    }
    for (int c = 0; c < 4; ++c) {
      const double on = std::max(y[c], 0.0);
      ++(on == 0.0 ? s->zero_columns : s->live_columns);
      for (int i = 0; i < 7; ++i) J(15 + i, c) = 2.0 * s->g(i, c) * on;
    }
  }
};

TEST(Rodas3, BlockEliminationWithSwitchingBorderColumnsMatchesDenseLu) {
  GatedBordered s;
  s.a.setZero();
  std::srand(17);
  using Matrix7 = Eigen::Matrix<double, 7, 7>;
  // Block 0: two lightly damped oscillators (about 6 and 4 Hz), so its states change sign often, the
  // second driven by the first: block lower triangular in 2 x 2 blocks, as the plant's spool and
  // pressures (the integrator's structured block inverse; block 1 takes the general one).
  s.a.block<4, 4>(0, 0) << -1.0, 40.0, 0.0, 0.0, -40.0, -1.0, 0.0, 0.0, 5.0, 2.0, -2.0, 25.0, 0.0, -3.0, -25.0, -2.0;
  s.a.block<4, 4>(4, 4) = Eigen::Matrix4d::Random() - 500.0 * Eigen::Matrix4d::Identity();
  s.a.block<4, 7>(0, 8) = 0.1 * Eigen::Matrix<double, 4, 7>::Random();             // blocks see x
  s.a.block<4, 7>(4, 15) = Eigen::Matrix<double, 4, 7>::Random();                  // and v
  s.a.block<7, 4>(15, 4) = Eigen::Matrix<double, 7, 4>::Random();                  // v' sees block 1 always
  s.g = Eigen::Matrix<double, 7, 4>::Random();                                     // and block 0 when on
  s.a.block<7, 7>(15, 8) = -4.0 * Matrix7::Identity() + 0.5 * Matrix7::Random();   // coupled springs
  s.a.block<7, 7>(15, 15) = -0.5 * Matrix7::Identity() + 0.1 * Matrix7::Random();  // and dampers
  s.a.block<7, 7>(8, 15) = Matrix7::Identity();                                    // x' = v
  // Rejected steps occur, so the structure kept from a Jacobian across a refactorisation is used.
  long rejected = 0;
  expectBlockEliminationMatchesDense(s, /*expect_halved_border=*/true, &rejected);
  EXPECT_GT(rejected, 0);
  // The pattern did switch: both states of the gate were seen by the Jacobians.
  EXPECT_GT(s.zero_columns, 100);
  EXPECT_GT(s.live_columns, 100);
}

TEST(Rodas3, RejectsBadConfiguration) {
  RosenbrockIntegrator r;
  const double atol[2] = {1e-6, 0.0};
  const RosenbrockSystem sys{&NonStiff::rhs, &NonStiff::jacobian, nullptr};
  EXPECT_THROW(r.configure(0, atol, 1e-6, 10, sys), std::invalid_argument);
  EXPECT_THROW(r.configure(2, atol, 1e-6, 10, sys), std::invalid_argument);  // atol 0
  EXPECT_THROW(r.configure(kMaxRosenbrockStates + 1, atol, 1e-6, 10, sys), std::invalid_argument);
  const double ok[3] = {1e-6, 1e-6, 1e-6};
  r.configure(3, ok, 1e-6, 10, sys);
  EXPECT_THROW(r.setBlockStructure(1), std::invalid_argument);  // 4 states > 3
}

}  // namespace
}  // namespace fullarm::plant
