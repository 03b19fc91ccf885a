#pragma once
// The non-stiff test system of the Rosenbrock tests (rosenbrock_test.cpp, rosenbrock_w_test.cpp)
// with its closed-form solution, and a fixed-step run of it.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>

#include "fullarm/plant/rosenbrock.hpp"

namespace fullarm::plant::test {

// y0' = y0 (1 - y0) (logistic), y1' = y2, y2' = -y1 (rotation): closed form
// y0 = 1 / (1 + 9 e^-t) from 0.1, (y1, y2) = (sin t, cos t) from (0, 1). `perturbation` scales a
// fixed dense matrix added to the true Jacobian (0, or a null `user`: the exact Jacobian).
struct NonStiff {
  double perturbation = 0.0;
  static void rhs(void* /*user*/, const double* y, double* f) noexcept {
    f[0] = y[0] * (1.0 - y[0]);
    f[1] = y[2];
    f[2] = -y[1];
  }
  static void jacobian(void* user, const double* y, double* f, double* j) noexcept {
    rhs(user, y, f);
    Eigen::Map<Eigen::Matrix3d> J(j);
    J.setZero();
    J(0, 0) = 1.0 - 2.0 * y[0];
    J(1, 2) = 1.0;
    J(2, 1) = -1.0;
    if (user == nullptr) return;
    Eigen::Matrix3d p;
    p << 0.3, 0.2, -0.1, 0.1, -0.4, 0.25, -0.2, 0.15, 0.35;
    J += static_cast<const NonStiff*>(user)->perturbation * p;
  }
};

inline Eigen::Vector3d nonStiffExact(double t) {
  return {1.0 / (1.0 + 9.0 * std::exp(-t)), std::sin(t), std::cos(t)};
}

// Error at t = 2 of a fixed-step run (every step accepted) from t = 0 with step h.
inline double fixedStepError(double h, RosenbrockMethod method = RosenbrockMethod::kRodas3, double perturbation = 0.0) {
  NonStiff system{perturbation};
  RosenbrockIntegrator r;
  r.setMethod(method);
  const double atol[3] = {1e3, 1e3, 1e3};  // every step accepted: a fixed-step run
  r.configure(3, atol, 1e-2, 10, {&NonStiff::rhs, &NonStiff::jacobian, &system});
  Eigen::Vector3d y(0.1, 0.0, 1.0);
  const int steps = static_cast<int>(std::lround(2.0 / h));
  for (int k = 0; k < steps; ++k) {
    r.resetStepSize(h);
    EXPECT_TRUE(r.advance(y.data(), h).ok());
  }
  EXPECT_EQ(r.stats().steps, steps);
  return (y - nonStiffExact(2.0)).norm();
}

}  // namespace fullarm::plant::test
