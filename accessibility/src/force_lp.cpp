#include "fullarm/accessibility/force_lp.hpp"

#include <ClpSimplex.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/contact_forces.hpp"

namespace fullarm::accessibility {
namespace {

const double kInf = COIN_DBL_MAX;               // CLP's infinity
constexpr double kCertificateTolerance = 1e-7;  // relative, on bounds, activities and reduced costs

/// Two unit vectors completing `d` to a right-handed orthonormal basis.
void orthogonalBasis(const Eigen::Vector3d& d, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  const Eigen::Vector3d seed = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  e1 = (seed - seed.dot(d) * d).normalized();
  e2 = d.cross(e1);
}

void checkProblem(const ForceProblem& p, const ForceLpOptions& o) {
  const Eigen::Index k = p.J_hand.cols();
  if (p.J_hand.rows() != 3) throw std::invalid_argument("force program: J_hand must have 3 rows");
  if (p.gravity_nm.size() != k || p.tau_min_nm.size() != k || p.tau_max_nm.size() != k) {
    throw std::invalid_argument("force program: gravity and torque limits must have one entry per J_hand column (" +
                                std::to_string(k) + ")");
  }
  if (std::abs(p.push_direction_W.norm() - 1.0) > 1e-9) {
    throw std::invalid_argument("force program: the push direction must be a unit vector");
  }
  for (Eigen::Index j = 0; j < k; ++j) {
    if (!(p.tau_min_nm[j] <= p.tau_max_nm[j])) {
      throw std::invalid_argument("force program: joint " + std::to_string(j) + " has tau_min " +
                                  std::to_string(p.tau_min_nm[j]) + " > tau_max " + std::to_string(p.tau_max_nm[j]));
    }
  }
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    const ForceContact& fc = p.contacts[c];
    if (fc.J_c.rows() != 3 || fc.J_c.cols() != k) {
      throw std::invalid_argument("force program: contact " + std::to_string(c) + " Jacobian must be 3 x " +
                                  std::to_string(k));
    }
    if (std::abs(fc.n_W.norm() - 1.0) > 1e-9) {
      throw std::invalid_argument("force program: contact " + std::to_string(c) + " normal must be a unit vector");
    }
  }
  if (!(o.friction_mu >= 0.0)) throw std::invalid_argument("force program: friction_mu must be >= 0");
  if (!(o.off_axis_force_max_n >= 0.0)) throw std::invalid_argument("force program: off_axis_force_max_n must be >= 0");
  if (!(o.drop_tolerance >= 0.0)) throw std::invalid_argument("force program: drop_tolerance must be >= 0");
}

}  // namespace

const char* toString(ForceStatus status) noexcept {
  switch (status) {
    case ForceStatus::kOptimal:
      return "optimal";
    case ForceStatus::kCannotHold:
      return "cannot hold";
    case ForceStatus::kUnbounded:
      return "unbounded";
    case ForceStatus::kSolverFailed:
      return "solver failed";
  }
  return "solver failed";
}

ForceLpResult solveForceLp(const ForceProblem& problem, const ForceLpOptions& options) {
  checkProblem(problem, options);
  const Eigen::Index k = problem.J_hand.cols();
  const Eigen::Vector3d& d = problem.push_direction_W;
  Eigen::Vector3d e1;
  Eigen::Vector3d e2;
  orthogonalBasis(d, e1, e2);
  const bool off_axis = options.off_axis_force_max_n > 0.0;
  const bool friction = options.friction_mu > 0.0;

  // Columns: s, [f_e1, f_e2], then per contact lambda_c (frictionless) or the four pyramid edge
  // weights beta_ck (force along n_c + mu t_k). Each column is the world force direction it
  // applies at its point; its joint-torque column is J^T times that direction.
  std::vector<Eigen::VectorXd> columns;
  std::vector<double> lower;
  std::vector<double> upper;
  std::vector<int> column_contact;            // -1 for the hand's columns
  std::vector<Eigen::Vector3d> column_force;  // world force per unit of the column
  auto add = [&](const Eigen::MatrixXd& J, const Eigen::Vector3d& dir, double lo, double hi, int contact) {
    columns.push_back(J.transpose() * dir);
    lower.push_back(lo);
    upper.push_back(hi);
    column_contact.push_back(contact);
    column_force.push_back(dir);
  };
  add(problem.J_hand, d, 0.0, kInf, -1);
  if (off_axis) {
    add(problem.J_hand, e1, -options.off_axis_force_max_n, options.off_axis_force_max_n, -1);
    add(problem.J_hand, e2, -options.off_axis_force_max_n, options.off_axis_force_max_n, -1);
  }
  for (std::size_t c = 0; c < problem.contacts.size(); ++c) {
    const ForceContact& fc = problem.contacts[c];
    if (!friction) {
      add(fc.J_c, fc.n_W, 0.0, kInf, static_cast<int>(c));
    } else {
      Eigen::Vector3d t1;
      Eigen::Vector3d t2;
      orthogonalBasis(fc.n_W, t1, t2);
      for (const Eigen::Vector3d& t : {t1, Eigen::Vector3d(-t1), t2, Eigen::Vector3d(-t2)}) {
        add(fc.J_c, Eigen::Vector3d(fc.n_W + options.friction_mu * t), 0.0, kInf, static_cast<int>(c));
      }
    }
  }

  const int num_cols = static_cast<int>(columns.size());
  const int num_rows = static_cast<int>(k);
  std::vector<CoinBigIndex> start{0};
  std::vector<int> index;
  std::vector<double> value;
  for (const Eigen::VectorXd& col : columns) {
    for (int r = 0; r < num_rows; ++r) {
      if (std::abs(col[r]) > options.drop_tolerance) {
        index.push_back(r);
        value.push_back(col[r]);
      }
    }
    start.push_back(static_cast<CoinBigIndex>(index.size()));
  }
  std::vector<double> objective(static_cast<std::size_t>(num_cols), 0.0);
  objective[0] = -1.0;  // CLP minimises: min -s
  std::vector<double> row_lower(static_cast<std::size_t>(num_rows));
  std::vector<double> row_upper(static_cast<std::size_t>(num_rows));
  for (int r = 0; r < num_rows; ++r) {
    row_lower[static_cast<std::size_t>(r)] = problem.tau_min_nm[r] - problem.gravity_nm[r];
    row_upper[static_cast<std::size_t>(r)] = problem.tau_max_nm[r] - problem.gravity_nm[r];
  }

  // CLP's optimum is accepted only with its certificate: the primal point within its bounds, and
  // the row duals y giving reduced costs c - A^T y of the right sign at every bound (optimality
  // conditions checked here, not taken from CLP's status). A failed check is retried once with the
  // other simplex algorithm from scratch.
  auto certified = [&](const ClpSimplex& lp) {
    const double* x = lp.getColSolution();
    const double* y = lp.dualRowSolution();
    double y_max = 0.0;
    for (int r = 0; r < num_rows; ++r) y_max = std::max(y_max, std::abs(y[r]));
    const double dual_tol = kCertificateTolerance * (1.0 + y_max);
    auto at = [](double v, double bound) {
      return std::abs(v - bound) <= kCertificateTolerance * (1.0 + std::abs(bound));
    };
    Eigen::VectorXd activity = Eigen::VectorXd::Zero(num_rows);
    for (int c = 0; c < num_cols; ++c) {
      const auto cu = static_cast<std::size_t>(c);
      if (!std::isfinite(x[c])) return false;
      if (x[c] < lower[cu] - kCertificateTolerance * (1.0 + std::abs(lower[cu])) ||
          (upper[cu] < kInf && x[c] > upper[cu] + kCertificateTolerance * (1.0 + std::abs(upper[cu])))) {
        return false;
      }
      activity += x[c] * columns[cu];
      double reduced = objective[cu];
      for (int r = 0; r < num_rows; ++r) reduced -= columns[cu][r] * y[r];
      const bool at_lower = at(x[c], lower[cu]);
      const bool at_upper = upper[cu] < kInf && at(x[c], upper[cu]);
      if (at_lower && at_upper) continue;
      if (at_lower ? reduced < -dual_tol : at_upper ? reduced > dual_tol : std::abs(reduced) > dual_tol) return false;
    }
    for (int r = 0; r < num_rows; ++r) {
      const auto ru = static_cast<std::size_t>(r);
      if (activity[r] < row_lower[ru] - kCertificateTolerance * (1.0 + std::abs(row_lower[ru])) ||
          activity[r] > row_upper[ru] + kCertificateTolerance * (1.0 + std::abs(row_upper[ru]))) {
        return false;
      }
      const bool at_lower = at(activity[r], row_lower[ru]);
      const bool at_upper = at(activity[r], row_upper[ru]);
      if (at_lower && at_upper) continue;
      if (at_lower ? y[r] < -dual_tol : at_upper ? y[r] > dual_tol : std::abs(y[r]) > dual_tol) return false;
    }
    return true;
  };

  std::optional<ClpSimplex> solved;
  const LpAlgorithm other = options.algorithm == LpAlgorithm::kDual ? LpAlgorithm::kPrimal : LpAlgorithm::kDual;
  bool optimum_certified = false;
  for (const LpAlgorithm algorithm : {options.algorithm, other}) {
    ClpSimplex& lp = solved.emplace();
    lp.setLogLevel(0);
    lp.loadProblem(num_cols, num_rows, start.data(), index.data(), value.data(), lower.data(), upper.data(),
                   objective.data(), row_lower.data(), row_upper.data());
    if (algorithm == LpAlgorithm::kDual) {
      lp.dual();
    } else {
      lp.primal();
    }
    if (lp.status() != 0) break;
    optimum_certified = certified(lp);
    if (optimum_certified) break;
  }

  const ClpSimplex& lp = *solved;
  ForceLpResult result;
  switch (lp.status()) {
    case 0:
      if (!optimum_certified) {
        result.status = ForceStatus::kSolverFailed;
        result.message = "CLP's optimum failed the optimality check with both simplex algorithms";
        return result;
      }
      result.status = ForceStatus::kOptimal;
      break;
    case 1:
      result.status = ForceStatus::kCannotHold;
      result.message = "infeasible: no muscle torques within the limits hold the arm here, even without a push";
      return result;
    case 2:
      result.status = ForceStatus::kUnbounded;
      result.message = "unbounded: no torque limit binds the push (its line runs through the joints)";
      return result;
    default:
      result.status = ForceStatus::kSolverFailed;
      result.message = "CLP stopped with status " + std::to_string(lp.status()) + " (secondary status " +
                       std::to_string(lp.secondaryStatus()) + ")";
      return result;
  }

  const double* x = lp.getColSolution();
  result.push_n = x[0];
  result.hand_force_W = x[0] * d;
  if (off_axis) result.hand_force_W += x[1] * e1 + x[2] * e2;
  result.tau_nm = problem.gravity_nm;
  for (int c = 0; c < num_cols; ++c) result.tau_nm += x[c] * columns[static_cast<std::size_t>(c)];
  for (Eigen::Index j = 0; j < k; ++j) {
    const double tol_hi = kActiveLimitTolerance_nm * std::max(1.0, std::abs(problem.tau_max_nm[j]));
    const double tol_lo = kActiveLimitTolerance_nm * std::max(1.0, std::abs(problem.tau_min_nm[j]));
    if (result.tau_nm[j] >= problem.tau_max_nm[j] - tol_hi) {
      result.active.push_back({static_cast<int>(j), true});
    } else if (result.tau_nm[j] <= problem.tau_min_nm[j] + tol_lo) {
      result.active.push_back({static_cast<int>(j), false});
    }
  }
  result.contacts.assign(problem.contacts.size(), ContactForce{});
  for (int c = 0; c < num_cols; ++c) {
    const int contact = column_contact[static_cast<std::size_t>(c)];
    if (contact < 0) continue;
    ContactForce& cf = result.contacts[static_cast<std::size_t>(contact)];
    const double weight = x[c];
    cf.normal_n += weight;  // every column of a contact has unit normal component
    cf.force_W += weight * column_force[static_cast<std::size_t>(c)];
  }
  return result;
}

ForceProblem buildForceProblem(const arm::ArmModel& model, const HumanArm& human, const arm::ArmData& fk,
                               const Eigen::Vector3d& push_direction_W, std::span<const haptics::LocalMinimum> minima,
                               const PushOptions& options) {
  const std::vector<int> joints = human.jointIndices();
  const auto k = static_cast<Eigen::Index>(joints.size());
  auto select = [&](const arm::PointJacobian& J) {
    Eigen::MatrixXd out(3, k);
    for (Eigen::Index i = 0; i < k; ++i) out.col(i) = J.block<3, 1>(0, joints[static_cast<std::size_t>(i)]);
    return out;
  };
  ForceProblem p;
  p.push_direction_W = push_direction_W.normalized();
  arm::PointJacobian J;
  arm::computePointJacobian(model, fk, model.tool_link, fk.X_WT.translation(), J);
  p.J_hand = select(J);
  const Eigen::VectorXd g = computeHumanGravityTorques(model, human, fk);
  p.gravity_nm.resize(k);
  for (Eigen::Index i = 0; i < k; ++i) p.gravity_nm[i] = g[joints[static_cast<std::size_t>(i)]];
  computeTorqueLimits(human, fk.q, p.tau_min_nm, p.tau_max_nm);
  for (std::size_t m = 0; m < minima.size(); ++m) {
    const haptics::LocalMinimum& lm = minima[m];
    if (lm.link < 0 || lm.link >= model.numJoints() || haptics::isHandLink(model, lm.link)) continue;
    if (!(lm.distance_m < options.contact_distance_m)) continue;
    const Eigen::Vector3d p_W = arm::pointInWorld(fk, lm.link, lm.p_L);
    arm::computePointJacobian(model, fk, lm.link, p_W, J);
    ForceContact c;
    c.J_c = select(J);
    c.n_W = lm.u_W.normalized();
    c.link = lm.link;
    c.minimum = static_cast<int>(m);
    p.contacts.push_back(std::move(c));
  }
  return p;
}

PushAnalysis analysePush(const arm::ArmModel& model, const HumanArm& human, const arm::ArmData& fk,
                         const Eigen::Vector3d& push_direction_W, std::span<const haptics::LocalMinimum> minima,
                         const PushOptions& options) {
  ForceProblem p = buildForceProblem(model, human, fk, push_direction_W, minima, options);
  PushAnalysis a;
  a.braced = solveForceLp(p, options.lp);
  a.contacts = p.contacts;
  p.contacts.clear();
  a.unbraced = solveForceLp(p, options.lp);
  if (a.braced.status == ForceStatus::kOptimal && a.unbraced.status == ForceStatus::kOptimal &&
      a.unbraced.push_n > 0.0) {
    a.leverage = a.braced.push_n / a.unbraced.push_n;
  } else if (a.braced.status == ForceStatus::kOptimal && a.braced.push_n > 0.0 &&
             (a.unbraced.status == ForceStatus::kCannotHold ||
              (a.unbraced.status == ForceStatus::kOptimal && a.unbraced.push_n == 0.0))) {
    a.leverage = std::numeric_limits<double>::infinity();
  }
  return a;
}

}  // namespace fullarm::accessibility
