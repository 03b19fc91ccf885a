#include "fullarm/design/lti.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <unsupported/Eigen/MatrixFunctions>

namespace fullarm::design {

namespace {

// Diagonal similarity D^-1 M D with powers of two (exact in floating point) that makes each
// row and column of M comparable in norm (Parlett & Reinsch 1969, as LAPACK dgebal without
// permutations). The hydraulic joint mixes pressures (1e7 Pa) with a normalised spool, and the
// exponential of the unbalanced matrix loses digits in its small entries.
// T2: diagonal balancing (reports/equations.md).
Eigen::VectorXd balance(Eigen::MatrixXd& M) {
  const Eigen::Index n = M.rows();
  Eigen::VectorXd d = Eigen::VectorXd::Ones(n);
  bool changed = true;
  for (int sweep = 0; changed && sweep < 100; ++sweep) {
    changed = false;
    for (Eigen::Index i = 0; i < n; ++i) {
      const double c = M.col(i).cwiseAbs().sum() - std::abs(M(i, i));
      const double r = M.row(i).cwiseAbs().sum() - std::abs(M(i, i));
      if (c == 0.0 || r == 0.0) continue;
      double f = 1.0;
      double cc = c;
      double rr = r;
      while (cc < rr / 2.0) {
        cc *= 2.0;
        rr /= 2.0;
        f *= 2.0;
      }
      while (cc >= rr * 2.0) {
        cc /= 2.0;
        rr *= 2.0;
        f /= 2.0;
      }
      if ((cc + rr) < 0.95 * (c + r)) {
        changed = true;
        d[i] *= f;
        M.col(i) *= f;
        M.row(i) /= f;
      }
    }
  }
  return d;
}

std::string sizeText(const Eigen::MatrixXd& m) {
  return std::to_string(m.rows()) + "x" + std::to_string(m.cols());
}

}  // namespace

void checkStateSpace(const StateSpace& sys, const char* what) {
  const Eigen::Index n = sys.A.rows();
  const bool ok = sys.A.cols() == n && sys.B.rows() == n && sys.C.cols() == n && sys.D.rows() == sys.C.rows() &&
                  sys.D.cols() == sys.B.cols();
  if (!ok) {
    throw std::invalid_argument(std::string(what) + ": inconsistent state-space sizes A " + sizeText(sys.A) + ", B " +
                                sizeText(sys.B) + ", C " + sizeText(sys.C) + ", D " + sizeText(sys.D));
  }
  if (!(sys.sample_time_s >= 0.0) || !std::isfinite(sys.sample_time_s)) {
    throw std::invalid_argument(std::string(what) + ": sample time must be finite and >= 0");
  }
}

// T1: ZOH discretisation (reports/equations.md).
StateSpace discretizeZoh(const StateSpace& sys, double dt_s) {
  checkStateSpace(sys, "discretizeZoh");
  if (sys.isDiscrete()) throw std::invalid_argument("discretizeZoh: the system is already discrete");
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) throw std::invalid_argument("discretizeZoh: dt_s must be > 0");
  const Eigen::Index n = sys.numStates();
  const Eigen::Index m = sys.numInputs();
  // Augmented exponential: exp([[A, B], [0, 0]] dt) = [[Phi, Gamma], [0, I]].
  Eigen::MatrixXd M = Eigen::MatrixXd::Zero(n + m, n + m);
  M.topLeftCorner(n, n) = sys.A * dt_s;
  M.topRightCorner(n, m) = sys.B * dt_s;
  // exp(M) = D exp(D^-1 M D) D^-1 with the balancing D.
  const Eigen::VectorXd scale = balance(M);
  const Eigen::MatrixXd Eb = M.exp();
  const Eigen::MatrixXd E = scale.asDiagonal() * Eb * scale.cwiseInverse().asDiagonal();
  StateSpace d;
  d.A = E.topLeftCorner(n, n);
  d.B = E.topRightCorner(n, m);
  d.C = sys.C;
  d.D = sys.D;
  d.sample_time_s = dt_s;
  return d;
}

StateSpace addInputDelay(const StateSpace& sys, int samples) {
  checkStateSpace(sys, "addInputDelay");
  if (!sys.isDiscrete()) throw std::invalid_argument("addInputDelay: the system must be discrete");
  if (samples < 0) throw std::invalid_argument("addInputDelay: samples must be >= 0");
  if (samples == 0) return sys;
  const Eigen::Index n = sys.numStates();
  const Eigen::Index m = sys.numInputs();
  const Eigen::Index r = static_cast<Eigen::Index>(samples) * m;
  // States [x; r_1; ...; r_d]: r_1[k+1] = u[k], r_i[k+1] = r_{i-1}[k], applied input r_d.
  StateSpace d;
  d.sample_time_s = sys.sample_time_s;
  d.A = Eigen::MatrixXd::Zero(n + r, n + r);
  d.B = Eigen::MatrixXd::Zero(n + r, m);
  d.C = Eigen::MatrixXd::Zero(sys.numOutputs(), n + r);
  d.D = Eigen::MatrixXd::Zero(sys.numOutputs(), m);
  d.A.topLeftCorner(n, n) = sys.A;
  d.A.block(0, n + r - m, n, m) = sys.B;
  for (int i = 1; i < samples; ++i) d.A.block(n + i * m, n + (i - 1) * m, m, m).setIdentity();
  d.B.block(n, 0, m, m).setIdentity();
  d.C.leftCols(n) = sys.C;
  d.C.rightCols(m) = sys.D;
  return d;
}

Eigen::MatrixXcd frequencyResponse(const StateSpace& sys, double w_radps) {
  const std::complex<double> point =
      sys.isDiscrete() ? std::polar(1.0, w_radps * sys.sample_time_s) : std::complex<double>(0.0, w_radps);
  if (sys.numStates() == 0) return sys.D.cast<std::complex<double>>();
  Eigen::MatrixXcd M = -sys.A.cast<std::complex<double>>();
  M.diagonal().array() += point;
  const Eigen::MatrixXcd X = M.partialPivLu().solve(sys.B.cast<std::complex<double>>());
  return sys.C.cast<std::complex<double>>() * X + sys.D.cast<std::complex<double>>();
}

Eigen::VectorXcd eigenvalues(const Eigen::MatrixXd& A) {
  if (A.rows() == 0) return Eigen::VectorXcd(0);
  Eigen::EigenSolver<Eigen::MatrixXd> solver(A, false);
  if (solver.info() != Eigen::Success) throw std::runtime_error("eigenvalues: the QR iteration did not converge");
  return solver.eigenvalues();
}

double spectralRadius(const Eigen::MatrixXd& A) {
  if (A.rows() == 0) return 0.0;
  return eigenvalues(A).cwiseAbs().maxCoeff();
}

double spectralAbscissa(const Eigen::MatrixXd& A) {
  if (A.rows() == 0) return -std::numeric_limits<double>::infinity();
  return eigenvalues(A).real().maxCoeff();
}

bool isStable(const StateSpace& sys) {
  return sys.isDiscrete() ? spectralRadius(sys.A) < 1.0 : spectralAbscissa(sys.A) < 0.0;
}

Eigen::VectorXd logspace(double w_min, double w_max, int count) {
  if (!(w_min > 0.0) || !(w_max > w_min) || count < 2) {
    throw std::invalid_argument("logspace: expected 0 < w_min < w_max and count >= 2");
  }
  Eigen::VectorXd w(count);
  const double a = std::log(w_min);
  const double b = std::log(w_max);
  for (int i = 0; i < count; ++i) w[i] = std::exp(a + (b - a) * i / (count - 1));
  return w;
}

}  // namespace fullarm::design
