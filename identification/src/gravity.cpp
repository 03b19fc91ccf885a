#include "fullarm/identification/gravity.hpp"

#include <Eigen/SVD>

#include <cmath>
#include <stdexcept>
#include <string>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"

namespace fullarm::identification {

Eigen::MatrixXd gravityRegressor(const arm::ArmModel& model, const Eigen::VectorXd& q) {
  const int n = model.numJoints();
  if (q.size() != n) {
    throw std::invalid_argument("gravity regressor: posture of " + std::to_string(q.size()) + " angles for " +
                                std::to_string(n) + " joints");
  }
  // I8: g is linear in (m, m c) of each link; each column is the gravity of one unit of one
  // parameter with every other link massless.
  arm::ArmModel unit = model;
  for (auto& j : unit.joints) {
    j.inertial.mass_kg = 0.0;
    j.inertial.com_m.setZero();
  }
  arm::ArmData data(unit);
  Eigen::MatrixXd y(n, 4 * n);
  for (int i = 0; i < n; ++i) {
    auto& link = unit.joints[static_cast<std::size_t>(i)].inertial;
    link.mass_kg = 1.0;
    link.com_m.setZero();
    arm::computeGravityTorques(unit, data, q);
    const Eigen::VectorXd mass_column = data.tau_gravity;
    y.col(4 * i) = mass_column;
    for (int a = 0; a < 3; ++a) {
      link.com_m.setZero();
      link.com_m[a] = 1.0;
      arm::computeGravityTorques(unit, data, q);
      y.col(4 * i + 1 + a) = data.tau_gravity - mass_column;
    }
    link.mass_kg = 0.0;
    link.com_m.setZero();
  }
  return y;
}

Eigen::VectorXd gravityParameters(const arm::ArmModel& model) {
  const int n = model.numJoints();
  Eigen::VectorXd pi(4 * n);
  for (int i = 0; i < n; ++i) {
    const auto& link = model.joints[static_cast<std::size_t>(i)].inertial;
    pi[4 * i] = link.mass_kg;
    pi.segment<3>(4 * i + 1) = link.mass_kg * link.com_m;
  }
  return pi;
}

arm::ArmModel withGravityParameters(const arm::ArmModel& model, const Eigen::VectorXd& pi) {
  const int n = model.numJoints();
  if (pi.size() != 4 * n) throw std::invalid_argument("gravity parameters: wrong size");
  arm::ArmModel out = model;
  for (int i = 0; i < n; ++i) {
    auto& link = out.joints[static_cast<std::size_t>(i)].inertial;
    const double m = pi[4 * i];
    if (!(m > 0.0)) {
      if (model.joints[static_cast<std::size_t>(i)].inertial.mass_kg == 0.0 && m == 0.0) continue;
      throw std::invalid_argument("gravity parameters: link " + model.joints[static_cast<std::size_t>(i)].name +
                                  " gets mass " + std::to_string(m) + " kg (not physically consistent)");
    }
    link.mass_kg = m;
    link.com_m = pi.segment<3>(4 * i + 1) / m;
  }
  return out;
}

GravityFit fitGravityParameters(const arm::ArmModel& nominal, const std::vector<Eigen::VectorXd>& postures,
                                const std::vector<Eigen::VectorXd>& torques_nm) {
  const int n = nominal.numJoints();
  if (postures.empty() || postures.size() != torques_nm.size()) {
    throw std::invalid_argument("gravity fit: " + std::to_string(postures.size()) + " postures and " +
                                std::to_string(torques_nm.size()) + " torque vectors");
  }
  const auto holds = static_cast<Eigen::Index>(postures.size());
  Eigen::MatrixXd y(holds * n, 4 * n);
  Eigen::VectorXd tau(holds * n);
  for (Eigen::Index k = 0; k < holds; ++k) {
    const auto& t = torques_nm[static_cast<std::size_t>(k)];
    if (t.size() != n) throw std::invalid_argument("gravity fit: torque vector of the wrong size");
    y.middleRows(k * n, n) = gravityRegressor(nominal, postures[static_cast<std::size_t>(k)]);
    tau.segment(k * n, n) = t;
  }
  const Eigen::VectorXd pi_nom = gravityParameters(nominal);
  // Links without mass in the nominal model (massless frames) stay massless: only the columns of
  // massive links are fitted.
  std::vector<Eigen::Index> cols;
  for (int i = 0; i < n; ++i) {
    if (nominal.joints[static_cast<std::size_t>(i)].inertial.mass_kg > 0.0) {
      for (int a = 0; a < 4; ++a) cols.push_back(4 * i + a);
    }
  }
  Eigen::MatrixXd select = Eigen::MatrixXd::Zero(4 * n, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) select(cols[c], static_cast<Eigen::Index>(c)) = 1.0;
  const Eigen::MatrixXd y_free = y * select;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(y_free, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const double tol = 1e-9 * (sv.size() > 0 ? sv[0] : 0.0) * static_cast<double>(std::max(y_free.rows(), y_free.cols()));
  GravityFit fit;
  fit.rank = static_cast<int>((sv.array() > tol).count());
  const Eigen::MatrixXd u = svd.matrixU().leftCols(fit.rank);
  const Eigen::MatrixXd v = select * svd.matrixV().leftCols(fit.rank);
  const Eigen::VectorXd s = sv.head(fit.rank);
  // I8: minimum-norm correction of the nominal, pi_nom + V S^-1 U^T (tau - Y pi_nom).
  fit.parameters = pi_nom + v * (s.cwiseInverse().asDiagonal() * (u.transpose() * (tau - y * pi_nom)));
  fit.base_directions = v.transpose();
  fit.base_values = fit.base_directions * fit.parameters;
  const Eigen::VectorXd residual = tau - y * fit.parameters;
  fit.residual_rms_nm = Eigen::VectorXd::Zero(n);
  for (Eigen::Index k = 0; k < holds; ++k) fit.residual_rms_nm += residual.segment(k * n, n).cwiseAbs2();
  fit.residual_rms_nm = (fit.residual_rms_nm / static_cast<double>(holds)).cwiseSqrt();
  fit.positive_masses = true;
  for (int i = 0; i < n; ++i) {
    if (nominal.joints[static_cast<std::size_t>(i)].inertial.mass_kg > 0.0 && !(fit.parameters[4 * i] > 0.0)) {
      fit.positive_masses = false;
    }
  }
  return fit;
}

}  // namespace fullarm::identification
