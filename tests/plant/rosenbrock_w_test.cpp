// The Rosenbrock-W method ROS34PW2 (Rang & Angermann 2005) of RosenbrockIntegrator:
// order 3 at fixed steps against closed-form solutions with the exact Jacobian AND with a
// deliberately wrong one (the W property; Rodas3 drops to order 1 with the same wrong Jacobian,
// which shows the check can fail), the Jacobian built once per advance() and the factorisation
// reused, and a stiff nonlinear system whose Jacobian changes within a call against a
// tight-tolerance Rodas3 reference.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <cstdio>

#include "fullarm/plant/rosenbrock.hpp"
#include "rosenbrock_test_system.hpp"

namespace fullarm::plant {
namespace {

using test::fixedStepError;
using test::NonStiff;
using test::nonStiffExact;

// Observed orders between h = 0.1, 0.05, 0.025 (and 0.0125).
std::array<double, 3> observedOrders(RosenbrockMethod method, double perturbation) {
  std::array<double, 4> e{};
  for (int i = 0; i < 4; ++i) e[static_cast<std::size_t>(i)] = fixedStepError(0.1 / (1 << i), method, perturbation);
  return {std::log2(e[0] / e[1]), std::log2(e[1] / e[2]), std::log2(e[2] / e[3])};
}

TEST(RosenbrockW, OrderThreeWithExactAndWithWrongJacobian) {
  {
    const RosenbrockMethod method = RosenbrockMethod::kRos34pw2;
    for (const double perturbation : {0.0, 1.0}) {
      SCOPED_TRACE(perturbation);
      const auto orders = observedOrders(method, perturbation);
      std::printf("ROS34PW2, perturbation %.0f: observed orders %.3f %.3f %.3f\n", perturbation, orders[0], orders[1],
                  orders[2]);
      for (const double order : orders) EXPECT_NEAR(order, 3.0, 0.3);
    }
  }
}

// The control: Rodas3 is not a W-method; with the same wrong Jacobian it drops well below order 3.
TEST(RosenbrockW, Rodas3LosesItsOrderWithTheWrongJacobian) {
  const auto exact = observedOrders(RosenbrockMethod::kRodas3, 0.0);
  const auto wrong = observedOrders(RosenbrockMethod::kRodas3, 1.0);
  std::printf("Rodas3: observed orders %.3f %.3f %.3f (exact J), %.3f %.3f %.3f (wrong J)\n", exact[0], exact[1],
              exact[2], wrong[0], wrong[1], wrong[2]);
  EXPECT_NEAR(exact[2], 3.0, 0.3);
  EXPECT_LT(wrong[2], 1.5);  // measured 1.0
}

// A W-method builds the Jacobian once per advance() (plus a refresh after two rejections in a
// row), evaluates f itself at the later steps, and factorises again only when h changes.
TEST(RosenbrockW, JacobianOncePerCallAndFactorisationReused) {
  {
    const RosenbrockMethod method = RosenbrockMethod::kRos34pw2;
    NonStiff system;
    RosenbrockIntegrator r;
    r.setMethod(method);
    const double atol[3] = {1e-8, 1e-8, 1e-8};
    r.configure(3, atol, 1e-8, 100000, {&NonStiff::rhs, &NonStiff::jacobian, &system});
    Eigen::Vector3d y(0.1, 0.0, 1.0);
    const int calls = 20;
    for (int k = 0; k < calls; ++k) ASSERT_TRUE(r.advance(y.data(), 0.1).ok());
    const RosenbrockStats& s = r.stats();
    EXPECT_LT((y - nonStiffExact(2.0)).cwiseAbs().maxCoeff(), 1e-6);
    EXPECT_GT(s.steps, 5 * calls);  // several steps per call, so the reuse is exercised
    EXPECT_GE(s.jac_evals, calls);
    EXPECT_LE(s.jac_evals, calls + s.rejected / 2);
    const long attempts = s.steps + s.rejected;
    EXPECT_LT(s.factorizations, attempts);  // equal steps within a call share G
    // f: one inside each Jacobian pass, (stages - 1) per attempt, f(y0) at every accepted step
    // that is not the last of its call (and not followed by a Jacobian refresh).
    const long stages = 4;
    EXPECT_LE(s.rhs_evals, s.jac_evals + (stages - 1) * attempts + s.steps - calls);
    EXPECT_GE(s.rhs_evals, (stages - 1) * attempts + s.steps);
  }
}

// y' = -1000 (1 + y^2) (y - s) + c, s' = c, c' = -s: a stiff nonlinear component (its Jacobian
// entry -1000 (1 + 3 y^2 - 2 y s) changes by a factor of up to about 3 within a call) tracking 1.5 sin t.
// Calls of 0.25 s, so the W-method's Jacobian is up to 0.25 s old; reference: Rodas3 (exact
// Jacobian at every step) at rtol 1e-11.
struct StiffNonlinear {
  static void rhs(void* /*user*/, const double* y, double* f) noexcept {
    f[0] = -1000.0 * (1.0 + y[0] * y[0]) * (y[0] - y[1]) + y[2];
    f[1] = y[2];
    f[2] = -y[1];
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    Eigen::Map<Eigen::Matrix3d> J(j);
    J.setZero();
    J(0, 0) = -1000.0 * (1.0 + 3.0 * y[0] * y[0] - 2.0 * y[0] * y[1]);
    J(0, 1) = 1000.0 * (1.0 + y[0] * y[0]);
    J(0, 2) = 1.0;
    J(1, 2) = 1.0;
    J(2, 1) = -1.0;
  }
};

Eigen::Vector3d integrateStiff(RosenbrockMethod method, double tol, RosenbrockStats* stats) {
  RosenbrockIntegrator r;
  r.setMethod(method);
  const double atol[3] = {tol, tol, tol};
  r.configure(3, atol, tol, 1000000, {&StiffNonlinear::rhs, &StiffNonlinear::jacobian, nullptr});
  Eigen::Vector3d y(0.0, 0.0, 1.5);  // s, c on a circle of radius 1.5: y swings to +-1.5
  for (int k = 0; k < 20; ++k) EXPECT_TRUE(r.advance(y.data(), 0.25).ok());
  if (stats != nullptr) *stats = r.stats();
  return y;
}

TEST(RosenbrockW, StiffNonlinearSystemWithAStaleJacobianMatchesTightReference) {
  const Eigen::Vector3d reference = integrateStiff(RosenbrockMethod::kRodas3, 1e-11, nullptr);
  RosenbrockStats rodas{};
  const Eigen::Vector3d y_rodas = integrateStiff(RosenbrockMethod::kRodas3, 1e-6, &rodas);
  const double rodas_error = (y_rodas - reference).cwiseAbs().maxCoeff();
  {
    const RosenbrockMethod method = RosenbrockMethod::kRos34pw2;
    RosenbrockStats w{};
    const Eigen::Vector3d y = integrateStiff(method, 1e-6, &w);
    EXPECT_LT((y - reference).cwiseAbs().maxCoeff(), 1e-4);
    EXPECT_LT((y - reference).cwiseAbs().maxCoeff(), 20.0 * std::max(rodas_error, 1e-7));
    EXPECT_LT(w.jac_evals, rodas.jac_evals / 5);  // the point of a W-method
    EXPECT_LT(w.steps + w.rejected, 3 * (rodas.steps + rodas.rejected));
  }
}

}  // namespace
}  // namespace fullarm::plant
