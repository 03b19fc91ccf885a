#include "fullarm/identification/gravity.hpp"

#include <Eigen/Cholesky>
#include <Eigen/SVD>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"

namespace fullarm::identification {
namespace {

/// A link's bounding geometry for its centre of mass: within `radius` of the segment a-b.
struct ComBound {
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

ComBound comBound(const arm::ArmModel& nominal, int i, const GravityBounds& bounds) {
  const auto& joint = nominal.joints[static_cast<std::size_t>(i)];
  if (joint.geometry.type == arm::LinkGeometry::Type::kCapsule) {
    return {joint.geometry.from_m, joint.geometry.to_m, joint.geometry.radius_m};
  }
  return {joint.inertial.com_m, joint.inertial.com_m, bounds.free_radius_m};
}

Eigen::Vector3d closestOnSegment(const ComBound& s, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = s.b - s.a;
  const double len2 = ab.squaredNorm();
  if (len2 <= 0.0) return s.a;
  const double t = std::clamp((c - s.a).dot(ab) / len2, 0.0, 1.0);
  return s.a + t * ab;
}

/// The holds stacked: Y (holds * joints x 4 joints), tau, and the columns of the links that have
/// mass in the nominal model (the fitted ones; massless frames stay massless).
struct StackedHolds {
  Eigen::MatrixXd y;
  Eigen::VectorXd tau;
  Eigen::MatrixXd select;  ///< 4 joints x free: pi = pi_nom + select (x - x_nom)
  Eigen::Index holds = 0;
};

StackedHolds stackHolds(const arm::ArmModel& nominal, const std::vector<Eigen::VectorXd>& postures,
                        const std::vector<Eigen::VectorXd>& torques_nm, const std::vector<int>& measured_joints) {
  const int n = nominal.numJoints();
  if (postures.empty() || postures.size() != torques_nm.size()) {
    throw std::invalid_argument("gravity fit: " + std::to_string(postures.size()) + " postures and " +
                                std::to_string(torques_nm.size()) + " torque vectors");
  }
  StackedHolds st;
  st.holds = static_cast<Eigen::Index>(postures.size());
  st.y.resize(st.holds * n, 4 * n);
  st.tau.resize(st.holds * n);
  for (Eigen::Index k = 0; k < st.holds; ++k) {
    const auto& t = torques_nm[static_cast<std::size_t>(k)];
    if (t.size() != n) throw std::invalid_argument("gravity fit: torque vector of the wrong size");
    st.y.middleRows(k * n, n) = gravityRegressor(nominal, postures[static_cast<std::size_t>(k)]);
    st.tau.segment(k * n, n) = t;
  }
  if (!measured_joints.empty()) {
    // A joint whose torque was not measured is a zero row: it neither pulls the fit nor adds rank.
    std::vector<bool> measured(static_cast<std::size_t>(n), false);
    for (const int j : measured_joints) {
      if (j < 0 || j >= n) {
        throw std::invalid_argument("gravity fit: measured joint index " + std::to_string(j) + " outside 0.." +
                                    std::to_string(n - 1));
      }
      measured[static_cast<std::size_t>(j)] = true;
    }
    for (Eigen::Index k = 0; k < st.holds; ++k) {
      for (int j = 0; j < n; ++j) {
        if (measured[static_cast<std::size_t>(j)]) continue;
        st.y.row(k * n + j).setZero();
        st.tau[k * n + j] = 0.0;
      }
    }
  }
  std::vector<Eigen::Index> cols;
  for (int i = 0; i < n; ++i) {
    if (nominal.joints[static_cast<std::size_t>(i)].inertial.mass_kg > 0.0) {
      for (int a = 0; a < 4; ++a) cols.push_back(4 * i + a);
    }
  }
  st.select = Eigen::MatrixXd::Zero(4 * n, static_cast<Eigen::Index>(cols.size()));
  for (std::size_t c = 0; c < cols.size(); ++c) st.select(cols[c], static_cast<Eigen::Index>(c)) = 1.0;
  return st;
}

/// Residual per joint, positive masses and centres inside for fit.parameters.
void finishFit(const arm::ArmModel& nominal, const StackedHolds& st, const GravityBounds& bounds, GravityFit& fit) {
  const int n = nominal.numJoints();
  fit.base_values = fit.base_directions * fit.parameters;
  const Eigen::VectorXd residual = st.tau - st.y * fit.parameters;
  fit.residual_rms_nm = Eigen::VectorXd::Zero(n);
  for (Eigen::Index k = 0; k < st.holds; ++k) fit.residual_rms_nm += residual.segment(k * n, n).cwiseAbs2();
  fit.residual_rms_nm = (fit.residual_rms_nm / static_cast<double>(st.holds)).cwiseSqrt();
  fit.positive_masses = true;
  fit.centres_inside = true;
  for (int i = 0; i < n; ++i) {
    if (!(nominal.joints[static_cast<std::size_t>(i)].inertial.mass_kg > 0.0)) continue;
    const double m = fit.parameters[4 * i];
    if (!(m > 0.0)) {
      fit.positive_masses = false;
      fit.centres_inside = false;
      continue;
    }
    const Eigen::Vector3d c = fit.parameters.segment<3>(4 * i + 1) / m;
    if (!centreOfMassInside(nominal, i, c, bounds, 1e-6)) fit.centres_inside = false;
  }
}

}  // namespace

bool centreOfMassInside(const arm::ArmModel& nominal, int i, const Eigen::Vector3d& com_m, const GravityBounds& bounds,
                        double slack_m) {
  const ComBound b = comBound(nominal, i, bounds);
  return (com_m - closestOnSegment(b, com_m)).norm() <= b.radius + slack_m;
}

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
                                const std::vector<Eigen::VectorXd>& torques_nm,
                                const std::vector<int>& measured_joints) {
  const StackedHolds st = stackHolds(nominal, postures, torques_nm, measured_joints);
  const Eigen::MatrixXd y_free = st.y * st.select;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(y_free, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const double tol = 1e-9 * (sv.size() > 0 ? sv[0] : 0.0) * static_cast<double>(std::max(y_free.rows(), y_free.cols()));
  GravityFit fit;
  fit.rank = static_cast<int>((sv.array() > tol).count());
  const Eigen::MatrixXd u = svd.matrixU().leftCols(fit.rank);
  const Eigen::MatrixXd v = st.select * svd.matrixV().leftCols(fit.rank);
  const Eigen::VectorXd s = sv.head(fit.rank);
  const Eigen::VectorXd pi_nom = gravityParameters(nominal);
  // I8: minimum-norm correction of the nominal, pi_nom + V S^-1 U^T (tau - Y pi_nom).
  fit.parameters = pi_nom + v * (s.cwiseInverse().asDiagonal() * (u.transpose() * (st.tau - st.y * pi_nom)));
  fit.base_directions = v.transpose();
  finishFit(nominal, st, GravityBounds{}, fit);
  return fit;
}

namespace {

/// min (x - x_star)^T A (x - x_star) over the consistent set, by a primal log-barrier method
/// with Newton steps (the Hessian's spread, from well to barely identified directions and the
/// tie weight, is no obstacle to Newton). Per massive link k (block x[4k..4k+3] = (m, h)):
/// m > m_min, and the centre of mass in its shape as a second-order cone: a ball is
/// |h - m a| < m r; a capsule adds s_k with 0 < s_k < m and |h - m a - s_k (b - a)| < m r
/// (s_k / m is the point along the segment). Starts strictly inside, near the nominal x_nom.
Eigen::VectorXd solveConsistent(const Eigen::MatrixXd& a_mat, const Eigen::VectorXd& x_star,
                                const Eigen::VectorXd& x_nom, const std::vector<int>& links,
                                const std::vector<ComBound>& shapes, double m_min) {
  const Eigen::Index nx = x_nom.size();
  std::vector<Eigen::Index> s_index(links.size(), -1);
  Eigen::Index dim = nx;
  for (std::size_t k = 0; k < links.size(); ++k) {
    if ((shapes[k].b - shapes[k].a).squaredNorm() > 0.0) s_index[k] = dim++;
  }
  // The start, strictly inside whatever the nominal is (the optimum does not depend on it): each
  // link's mass max(m_nom, 2 m_min), its centre of mass the nominal one moved to within half the
  // radius of the shape's segment (at a point 1 %..99 % along a capsule's), a capsule's s there.
  Eigen::VectorXd v = Eigen::VectorXd::Zero(dim);
  for (std::size_t k = 0; k < links.size(); ++k) {
    const auto o = static_cast<Eigen::Index>(4 * k);
    const ComBound& shape = shapes[k];
    const double m = std::max(x_nom[o], 2.0 * m_min);
    const Eigen::Vector3d c_nom = x_nom[o] > 0.0 ? Eigen::Vector3d(x_nom.segment<3>(o + 1) / x_nom[o]) : shape.a;
    const Eigen::Vector3d e = shape.b - shape.a;
    const double t = s_index[k] >= 0 ? std::clamp((c_nom - shape.a).dot(e) / e.squaredNorm(), 0.01, 0.99) : 0.0;
    const Eigen::Vector3d p = shape.a + t * e;
    const Eigen::Vector3d d = c_nom - p;
    const double dist = d.norm();
    const Eigen::Vector3d c = dist > 0.5 * shape.radius ? Eigen::Vector3d(p + d * (0.5 * shape.radius / dist)) : c_nom;
    v[o] = m;
    v.segment<3>(o + 1) = m * c;
    if (s_index[k] >= 0) v[s_index[k]] = t * m;
  }
  struct Cone {  // t = alpha^T v, u = B v
    Eigen::VectorXd alpha;
    Eigen::MatrixXd b;
  };
  std::vector<Eigen::VectorXd> linear;  // c = g^T v - offset > 0
  std::vector<double> offsets;
  std::vector<Cone> cones;
  for (std::size_t k = 0; k < links.size(); ++k) {
    const auto o = static_cast<Eigen::Index>(4 * k);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(dim);
    g[o] = 1.0;
    linear.push_back(g);
    offsets.push_back(m_min);
    Cone cone{Eigen::VectorXd::Zero(dim), Eigen::MatrixXd::Zero(3, dim)};
    cone.alpha[o] = shapes[k].radius;
    cone.b.block<3, 3>(0, o + 1).setIdentity();
    cone.b.col(o) = -shapes[k].a;
    if (s_index[k] >= 0) {
      cone.b.col(s_index[k]) = -(shapes[k].b - shapes[k].a);
      Eigen::VectorXd gs = Eigen::VectorXd::Zero(dim);
      gs[s_index[k]] = 1.0;
      linear.push_back(gs);
      offsets.push_back(0.0);
      gs[o] = 1.0;
      gs[s_index[k]] = -1.0;
      linear.push_back(gs);
      offsets.push_back(0.0);
    }
    cones.push_back(cone);
  }
  const auto barrier_count = static_cast<double>(linear.size() + 2 * cones.size());  // a cone counts 2
  // Objective on v (s does not enter): (x - x_star)^T A (x - x_star).
  auto objective = [&](const Eigen::VectorXd& vv) {
    const Eigen::VectorXd d = vv.head(nx) - x_star;
    return d.dot(a_mat * d);
  };
  // Barrier value, or +inf outside.
  auto barrier = [&](const Eigen::VectorXd& vv) {
    double phi = 0.0;
    for (std::size_t j = 0; j < linear.size(); ++j) {
      const double c = linear[j].dot(vv) - offsets[j];
      if (!(c > 0.0)) return std::numeric_limits<double>::infinity();
      phi -= std::log(c);
    }
    for (const auto& cone : cones) {
      const double t = cone.alpha.dot(vv);
      const double q = t * t - (cone.b * vv).squaredNorm();
      if (!(t > 0.0 && q > 0.0)) return std::numeric_limits<double>::infinity();
      phi -= std::log(q);
    }
    return phi;
  };
  if (!std::isfinite(barrier(v))) {
    throw std::invalid_argument("gravity fit: a link's bounding geometry has no interior (radius 0)");
  }
  const double f_scale = std::max(objective(v), 1e-300);
  double t_weight = barrier_count / f_scale;  // the barrier and objective start comparable
  Eigen::MatrixXd a_ext = Eigen::MatrixXd::Zero(dim, dim);
  a_ext.topLeftCorner(nx, nx) = a_mat;
  for (int outer = 0; outer < 60; ++outer) {
    for (int newton = 0; newton < 100; ++newton) {
      Eigen::VectorXd grad = Eigen::VectorXd::Zero(dim);
      grad.head(nx) = 2.0 * t_weight * (a_mat * (v.head(nx) - x_star));
      Eigen::MatrixXd hess = 2.0 * t_weight * a_ext;
      for (std::size_t j = 0; j < linear.size(); ++j) {
        const double c = linear[j].dot(v) - offsets[j];
        grad -= linear[j] / c;
        hess += linear[j] * linear[j].transpose() / (c * c);
      }
      for (const auto& cone : cones) {
        const double t = cone.alpha.dot(v);
        const Eigen::Vector3d u = cone.b * v;
        const double q = t * t - u.squaredNorm();
        const Eigen::VectorXd dq = 2.0 * t * cone.alpha - 2.0 * cone.b.transpose() * u;
        const Eigen::MatrixXd d2q = 2.0 * cone.alpha * cone.alpha.transpose() - 2.0 * cone.b.transpose() * cone.b;
        grad -= dq / q;
        hess += dq * dq.transpose() / (q * q) - d2q / q;
      }
      const Eigen::VectorXd step = -hess.ldlt().solve(grad);
      const double decrement = -grad.dot(step);
      if (!(decrement > 1e-14)) break;
      const double value = t_weight * objective(v) + barrier(v);
      // Backtracking to the Armijo condition; no step that meets it ends this centring.
      double alpha = 1.0;
      bool descent = false;
      for (int ls = 0; ls < 60 && !descent; ++ls) {
        const Eigen::VectorXd trial = v + alpha * step;
        const double b_trial = barrier(trial);
        descent = std::isfinite(b_trial) && t_weight * objective(trial) + b_trial <= value - 0.25 * alpha * decrement;
        if (!descent) alpha *= 0.5;
      }
      if (!descent) break;
      v += alpha * step;
    }
    if (barrier_count / t_weight < 1e-15 * f_scale) break;
    t_weight *= 8.0;
  }
  return v.head(nx);
}

}  // namespace

GravityFit fitConsistentGravityParameters(const arm::ArmModel& nominal, const std::vector<Eigen::VectorXd>& postures,
                                          const std::vector<Eigen::VectorXd>& torques_nm, const GravityBounds& bounds,
                                          const std::vector<int>& measured_joints) {
  const int n = nominal.numJoints();
  std::vector<int> links;        // model index of each massive link (free block k = links[k])
  std::vector<ComBound> shapes;  // its centre-of-mass bound
  for (int i = 0; i < n; ++i) {
    const auto& link = nominal.joints[static_cast<std::size_t>(i)];
    if (!(link.inertial.mass_kg > 0.0)) continue;
    links.push_back(i);
    shapes.push_back(comBound(nominal, i, bounds));
  }
  // Consistent within the solver's tolerance: the name of the first inconsistent link, or "".
  auto inconsistentLink = [&](const Eigen::VectorXd& pi) -> std::string {
    for (int i : links) {
      const double m = pi[4 * i];
      if (!(m >= bounds.min_mass_kg * (1.0 - 1e-9)) ||
          !centreOfMassInside(nominal, i, pi.segment<3>(4 * i + 1) / m, bounds, 1e-6)) {
        return nominal.joints[static_cast<std::size_t>(i)].name + " (mass " + std::to_string(m) + " kg)";
      }
    }
    return {};
  };
  GravityFit fit = fitGravityParameters(nominal, postures, torques_nm, measured_joints);
  if (inconsistentLink(fit.parameters).empty()) {
    fit.centres_inside = true;
    return fit;
  }

  const StackedHolds st = stackHolds(nominal, postures, torques_nm, measured_joints);
  const Eigen::MatrixXd y_free = st.y * st.select;
  const auto rows = static_cast<double>(y_free.rows());
  Eigen::MatrixXd a = y_free.transpose() * y_free / rows;
  const Eigen::VectorXd pi_nom = gravityParameters(nominal);
  const Eigen::VectorXd x_nom = st.select.transpose() * pi_nom;
  const double w = bounds.tie_weight * std::max(a.diagonal().maxCoeff(), 1e-300);
  a.diagonal().array() += w;
  const Eigen::VectorXd b = y_free.transpose() * st.tau / rows + w * x_nom;
  const Eigen::LLT<Eigen::MatrixXd> llt(a);
  if (llt.info() != Eigen::Success) throw std::runtime_error("gravity fit: the normal equations are not positive");
  const Eigen::VectorXd x_star = llt.solve(b);
  const Eigen::VectorXd x = solveConsistent(a, x_star, x_nom, links, shapes, bounds.min_mass_kg);
  fit.parameters = pi_nom + st.select * (x - x_nom);
  finishFit(nominal, st, bounds, fit);
  if (const std::string link = inconsistentLink(fit.parameters); !link.empty()) {
    throw std::runtime_error("gravity fit: the constrained solver ended with link " + link + " inconsistent");
  }
  return fit;
}

}  // namespace fullarm::identification
