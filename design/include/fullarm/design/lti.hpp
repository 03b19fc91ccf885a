#pragma once
/// @file
/// Small linear time-invariant toolkit for the controller analysis (offline, not @rt):
/// state-space models, zero-order-hold discretisation with input delay, frequency responses,
/// spectral radius. Dense Eigen matrices; sizes are a few tens of states.

#include <Eigen/Core>
#include <complex>

namespace fullarm::design {

/// x' = A x + B u, y = C x + D u (continuous, `sample_time_s` = 0) or
/// x[k+1] = A x[k] + B u[k], y[k] = C x[k] + D u[k] (discrete, `sample_time_s` > 0).
struct StateSpace {
  Eigen::MatrixXd A;
  Eigen::MatrixXd B;
  Eigen::MatrixXd C;
  Eigen::MatrixXd D;
  double sample_time_s = 0.0;  ///< 0: continuous time

  [[nodiscard]] Eigen::Index numStates() const noexcept { return A.rows(); }
  [[nodiscard]] Eigen::Index numInputs() const noexcept { return B.cols(); }
  [[nodiscard]] Eigen::Index numOutputs() const noexcept { return C.rows(); }
  [[nodiscard]] bool isDiscrete() const noexcept { return sample_time_s > 0.0; }
};

/// Checks that A is square and B, C, D conform.
/// @throws std::invalid_argument naming `what` and the offending sizes.
void checkStateSpace(const StateSpace& sys, const char* what);

/// Zero-order-hold discretisation at period `dt_s`: the augmented matrix exponential
/// exp([[A, B], [0, 0]] dt) = [[Phi, Gamma], [0, I]] (Franklin, Powell & Workman, Digital
/// Control of Dynamic Systems, 3rd ed., sec. 4.3.3); C and D are unchanged.
/// @throws std::invalid_argument if `sys` is discrete or `dt_s` <= 0.
[[nodiscard]] StateSpace discretizeZoh(const StateSpace& sys, double dt_s);

/// Appends `samples` whole periods of input delay to every input of a discrete system
/// (u applied at step k is the u given at step k - samples), as a shift register of
/// samples * numInputs() extra states.
/// @throws std::invalid_argument if `sys` is continuous or `samples` < 0.
[[nodiscard]] StateSpace addInputDelay(const StateSpace& sys, int samples);

/// Frequency response C (zI - A)^-1 B + D at s = j w (continuous) or z = e^{j w T}
/// (discrete), `w_radps` in rad/s. Size numOutputs() x numInputs().
[[nodiscard]] Eigen::MatrixXcd frequencyResponse(const StateSpace& sys, double w_radps);

/// Largest |eigenvalue| of A.
[[nodiscard]] double spectralRadius(const Eigen::MatrixXd& A);

/// Largest real part of the eigenvalues of A.
[[nodiscard]] double spectralAbscissa(const Eigen::MatrixXd& A);

/// Eigenvalues of A.
[[nodiscard]] Eigen::VectorXcd eigenvalues(const Eigen::MatrixXd& A);

/// Asymptotic stability: every eigenvalue in |z| < 1 (discrete) or Re s < 0 (continuous).
[[nodiscard]] bool isStable(const StateSpace& sys);

/// Logarithmically spaced frequencies from `w_min` to `w_max` (both > 0), `count` >= 2 points.
[[nodiscard]] Eigen::VectorXd logspace(double w_min, double w_max, int count);

}  // namespace fullarm::design
