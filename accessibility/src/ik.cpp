#include "fullarm/accessibility/ik.hpp"

#include <Eigen/Cholesky>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

#include "fullarm/arm/kinematics.hpp"

namespace fullarm::accessibility {
namespace {

constexpr int kArm = 7;        // the arm chain's joints
constexpr int kElbowLink = 3;  // origin of joint 4 (R_EB)
constexpr int kWristLink = 5;  // origin of joint 6 (R_WFE)

double wrapAngle(double a) {
  return std::remainder(a, 2.0 * std::numbers::pi);
}

Eigen::Matrix<double, 7, 1> residual(const arm::ArmModel& model, const arm::ArmData& fk, const Eigen::Vector3d& p,
                                     const Eigen::Matrix3d& R, double swivel) {
  Eigen::Matrix<double, 7, 1> e;
  e.head<3>() = p - fk.X_WT.translation();
  const Eigen::AngleAxisd aa(R * fk.X_WL[static_cast<std::size_t>(model.tool_link)].linear().transpose());
  e.segment<3>(3) = aa.angle() * aa.axis();
  e[6] = wrapAngle(swivel - swivelAngle(fk));
  return e;
}

}  // namespace

double swivelAngle(const arm::ArmData& fk) {
  const Eigen::Vector3d s = fk.o_W[0];
  const Eigen::Vector3d e = fk.o_W[kElbowLink] - s;
  const Eigen::Vector3d n = (fk.o_W[kWristLink] - s).normalized();
  Eigen::Vector3d r = -Eigen::Vector3d::UnitZ() + n.z() * n;  // -z projected off the line
  if (r.norm() < 1e-9) r = Eigen::Vector3d::UnitX() - n.x() * n;
  r.normalize();
  return std::atan2(n.cross(r).dot(e), r.dot(e));
}

IkSolution solveIk(const arm::ArmModel& model, arm::ArmData& fk, const Eigen::Vector3d& position_W_m,
                   const Eigen::Matrix3d& R_W, double swivel_rad, const Eigen::VectorXd& q_seed,
                   const IkOptions& options) {
  if (q_seed.size() != model.numJoints()) throw std::invalid_argument("solveIk: seed of the wrong size");
  const Eigen::VectorXd lo = model.lowerLimits();
  const Eigen::VectorXd hi = model.upperLimits();
  IkSolution sol;
  sol.swivel_rad = swivel_rad;
  sol.q_rad = q_seed.cwiseMax(lo).cwiseMin(hi);
  arm::PointJacobian Jp;
  Eigen::Matrix<double, 7, 7> J;
  Eigen::VectorXd qh = sol.q_rad;
  constexpr double kH = 1e-7;
  constexpr int kStallWindow = 20;
  constexpr double kStallRatio = 0.8;
  double window_residual = std::numeric_limits<double>::infinity();
  for (int it = 0; it <= options.max_iterations; ++it) {
    arm::computeForwardKinematics(model, fk, sol.q_rad);
    const Eigen::Matrix<double, 7, 1> e = residual(model, fk, position_W_m, R_W, swivel_rad);
    sol.position_error_m = e.head<3>().norm();
    sol.angle_error_rad = e.segment<3>(3).norm();
    sol.swivel_error_rad = std::abs(e[6]);
    sol.iterations = it;
    if (sol.position_error_m < options.position_tolerance_m && sol.angle_error_rad < options.angle_tolerance_rad &&
        sol.swivel_error_rad < options.angle_tolerance_rad) {
      sol.converged = true;
      return sol;
    }
    if (it == options.max_iterations) break;
    // Stalled (typically against a joint limit): the residual has not shrunk by a fifth over the
    // last kStallWindow steps. A converging solve gains far more than that per window.
    if (it % kStallWindow == 0) {
      const double residual_norm = e.norm();
      if (it > 0 && residual_norm > kStallRatio * window_residual) break;
      window_residual = residual_norm;
    }
    const double psi = swivelAngle(fk);
    arm::computePointJacobian(model, fk, model.tool_link, fk.X_WT.translation(), Jp);
    J.topRows<6>() = Jp.leftCols<kArm>();
    for (int j = 0; j < kArm; ++j) {  // d(swivel)/dq by forward differences
      qh = sol.q_rad;
      qh[j] += kH;
      arm::computeForwardKinematics(model, fk, qh);
      J(6, j) = wrapAngle(swivelAngle(fk) - psi) / kH;
    }
    // A1: damped least squares, dq = J^T (J J^T + lambda^2 I)^-1 e.
    const Eigen::Matrix<double, 7, 7> A =
        J * J.transpose() + options.damping * options.damping * Eigen::Matrix<double, 7, 7>::Identity();
    Eigen::Matrix<double, 7, 1> dq = J.transpose() * A.ldlt().solve(e);
    const double norm = dq.norm();
    if (norm > options.max_step_rad) dq *= options.max_step_rad / norm;
    sol.q_rad.head<kArm>() += dq;
    sol.q_rad = sol.q_rad.cwiseMax(lo).cwiseMin(hi);
  }
  return sol;
}

std::vector<IkSolution> sweepGoalConfigurations(const arm::ArmModel& model, const GraspTarget& target,
                                                const Eigen::VectorXd& q_seed, const IkOptions& options) {
  arm::ArmData fk(model);
  std::vector<IkSolution> out;
  const double two_pi = 2.0 * std::numbers::pi;
  for (int r = 0; r < options.roll_samples; ++r) {
    const double roll = -std::numbers::pi + two_pi * r / options.roll_samples;
    const Eigen::Matrix3d R = graspOrientation(target, roll);
    Eigen::VectorXd seed = q_seed;
    bool have_previous = false;
    for (int s = 0; s < options.swivel_samples; ++s) {
      const double swivel = -std::numbers::pi + two_pi * s / options.swivel_samples;
      IkSolution sol = solveIk(model, fk, target.position_W_m, R, swivel, seed, options);
      if (!sol.converged && have_previous) sol = solveIk(model, fk, target.position_W_m, R, swivel, q_seed, options);
      if (!sol.converged) {
        sol = solveIk(model, fk, target.position_W_m, R, swivel, model.defaultPosture(), options);
      }
      sol.roll_rad = roll;
      have_previous = sol.converged;
      if (sol.converged) {
        seed = sol.q_rad;
        out.push_back(std::move(sol));
      } else {
        seed = q_seed;
      }
    }
  }
  return out;
}

}  // namespace fullarm::accessibility
