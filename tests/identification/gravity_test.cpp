// Gravity base parameters against the arm's own gravity (arm::computeGravityTorques): the
// regressor reproduces g(q) of the default model, and noise-free holds of a perturbed model give
// its base parameters within 1 % and its torques at held-out postures. The physically consistent
// fit recovers a consistent truth the same way, and for a truth outside the bounds returns a
// consistent set whose residual is no worse than that of the truth projected into the bounds.

#include "fullarm/identification/gravity.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::identification {
namespace {

std::vector<Eigen::VectorXd> postures(const arm::ArmModel& model, int count, std::uint64_t stream) {
  std::vector<Eigen::VectorXd> out;
  const Eigen::VectorXd lo = model.lowerLimits();
  const Eigen::VectorXd hi = model.upperLimits();
  for (int k = 0; k < count; ++k) {
    core::RandomStream rng(21, stream, static_cast<std::uint64_t>(k));
    Eigen::VectorXd q(model.numJoints());
    for (int j = 0; j < q.size(); ++j) q[j] = rng.uniform(lo[j] + 0.05, hi[j] - 0.05);
    out.push_back(q);
  }
  return out;
}

Eigen::VectorXd gravity(const arm::ArmModel& model, const Eigen::VectorXd& q) {
  arm::ArmData data(model);
  arm::computeGravityTorques(model, data, q);
  return data.tau_gravity;
}

TEST(GravityTest, RegressorTimesParametersIsTheArmsGravity) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Eigen::VectorXd pi = gravityParameters(model);
  for (const auto& q : postures(model, 20, 1)) {
    const Eigen::VectorXd g = gravity(model, q);
    EXPECT_LT((gravityRegressor(model, q) * pi - g).cwiseAbs().maxCoeff(), 1e-9 * (1.0 + g.cwiseAbs().maxCoeff()));
  }
  const arm::ArmModel same = withGravityParameters(model, pi);
  for (std::size_t i = 0; i < model.joints.size(); ++i) {
    EXPECT_NEAR(same.joints[i].inertial.mass_kg, model.joints[i].inertial.mass_kg, 1e-12);
    EXPECT_LT((same.joints[i].inertial.com_m - model.joints[i].inertial.com_m).norm(), 1e-12);
  }
}

TEST(GravityTest, NoiseFreeHoldsRecoverTheBaseParameters) {
  const arm::ArmModel& nominal = arm::test::defaultModel();
  arm::ArmModel truth = nominal;
  for (std::size_t i = 0; i < truth.joints.size(); ++i) {
    auto& link = truth.joints[i].inertial;
    if (link.mass_kg <= 0.0) continue;
    link.mass_kg *= (i % 2 == 0) ? 0.8 : 1.15;  // the default is stronger than the reference
    link.com_m += Eigen::Vector3d(0.01, -0.005, 0.02);
  }
  const auto train = postures(nominal, 60, 2);
  std::vector<Eigen::VectorXd> torques;
  for (const auto& q : train) torques.push_back(gravity(truth, q));
  const GravityFit fit = fitGravityParameters(nominal, train, torques);
  EXPECT_GT(fit.rank, 0);
  EXPECT_LT(fit.rank, 4 * nominal.numJoints());  // some directions are never seen by holds
  EXPECT_TRUE(fit.positive_masses);
  const Eigen::VectorXd truth_base = fit.base_directions * gravityParameters(truth);
  for (Eigen::Index k = 0; k < truth_base.size(); ++k) {
    EXPECT_NEAR(fit.base_values[k], truth_base[k], 0.01 * std::abs(truth_base[k]) + 1e-9) << "base " << k;
  }
  EXPECT_LT(fit.residual_rms_nm.maxCoeff(), 1e-8);
  // Held-out postures: the fitted model's gravity is the truth's.
  const arm::ArmModel fitted = withGravityParameters(nominal, fit.parameters);
  for (const auto& q : postures(nominal, 20, 3)) {
    const Eigen::VectorXd g = gravity(truth, q);
    EXPECT_LT((gravity(fitted, q) - g).cwiseAbs().maxCoeff(), 1e-7 * (1.0 + g.cwiseAbs().maxCoeff()));
  }
  EXPECT_THROW((void)fitGravityParameters(nominal, train, {}), std::invalid_argument);
  Eigen::VectorXd negative = gravityParameters(nominal);
  negative[4 * 3] = -1.0;
  EXPECT_THROW((void)withGravityParameters(nominal, negative), std::invalid_argument);
}

/// Root mean square over all rows of the torque difference of two models at `qs`.
double rmsDifference(const arm::ArmModel& a, const arm::ArmModel& b, const std::vector<Eigen::VectorXd>& qs) {
  double sum = 0.0;
  Eigen::Index count = 0;
  for (const auto& q : qs) {
    sum += (gravity(a, q) - gravity(b, q)).squaredNorm();
    count += q.size();
  }
  return std::sqrt(sum / static_cast<double>(count));
}

TEST(GravityTest, ConsistentFitRecoversAConsistentTruthsBaseParameters) {
  const arm::ArmModel& nominal = arm::test::defaultModel();
  arm::ArmModel truth = nominal;
  for (std::size_t i = 0; i < truth.joints.size(); ++i) {
    auto& link = truth.joints[i].inertial;
    if (link.mass_kg <= 0.0) continue;
    link.mass_kg *= (i % 2 == 0) ? 0.75 : 1.2;
    link.com_m += Eigen::Vector3d(0.005, -0.005, 0.01);  // inside every capsule and the 0.05 m balls
  }
  const auto train = postures(nominal, 60, 4);
  std::vector<Eigen::VectorXd> torques;
  for (const auto& q : train) torques.push_back(gravity(truth, q));
  const GravityFit fit = fitConsistentGravityParameters(nominal, train, torques);
  EXPECT_TRUE(fit.positive_masses);
  EXPECT_TRUE(fit.centres_inside);
  const Eigen::VectorXd truth_base = fit.base_directions * gravityParameters(truth);
  for (Eigen::Index k = 0; k < truth_base.size(); ++k) {
    EXPECT_NEAR(fit.base_values[k], truth_base[k], 0.01 * std::abs(truth_base[k]) + 1e-9) << "base " << k;
  }
  EXPECT_LT(fit.residual_rms_nm.maxCoeff(), 1e-8);
}

TEST(GravityTest, ConsistentFitOfAnInfeasibleTruthStaysInsideAndMatchesWithinTheProjectionBound) {
  const arm::ArmModel& nominal = arm::test::defaultModel();
  const GravityBounds bounds;
  arm::ArmModel truth = nominal;
  // The forearm's centre of mass 0.3 m off its axis (capsule radius 0.04 m) and the wrist
  // flexion link's 0.3 m from its nominal (ball radius 0.05 m): the exact fit is outside, and
  // the other links' bounds cannot make up for it.
  const int forearm = 4;
  const int wrist = 5;
  truth.joints[forearm].inertial.com_m = Eigen::Vector3d(0.3, 0.0, -0.139);
  truth.joints[wrist].inertial.com_m = Eigen::Vector3d(0.0, 0.3, 0.0);
  const auto train = postures(nominal, 60, 5);
  std::vector<Eigen::VectorXd> torques;
  for (const auto& q : train) torques.push_back(gravity(truth, q));

  const GravityFit free_fit = fitGravityParameters(nominal, train, torques);
  EXPECT_FALSE(free_fit.centres_inside);
  const GravityFit fit = fitConsistentGravityParameters(nominal, train, torques, bounds);
  EXPECT_TRUE(fit.positive_masses);
  EXPECT_TRUE(fit.centres_inside);
  const arm::ArmModel fitted = withGravityParameters(nominal, fit.parameters);
  for (std::size_t i = 0; i < nominal.joints.size(); ++i) {
    if (nominal.joints[i].inertial.mass_kg <= 0.0) continue;
    EXPECT_GE(fitted.joints[i].inertial.mass_kg, bounds.min_mass_kg * (1.0 - 1e-9)) << nominal.joints[i].name;
    EXPECT_TRUE(centreOfMassInside(nominal, static_cast<int>(i), fitted.joints[i].inertial.com_m, bounds, 1e-6))
        << nominal.joints[i].name;
  }
  // Bound: the truth with each centre of mass moved to the nearest point of its bound is
  // feasible, so the optimum's objective is no larger than its objective:
  //   r_fit^2 <= r_proj^2 + w (|pi_proj - pi_nom|^2 - |pi_fit - pi_nom|^2) <= r_proj^2 + w |pi_proj - pi_nom|^2
  // with r the RMS torque residual over the holds and w the tie weight as the fit scales it.
  arm::ArmModel projected = truth;
  projected.joints[forearm].inertial.com_m = Eigen::Vector3d(0.04, 0.0, -0.139);
  projected.joints[wrist].inertial.com_m = Eigen::Vector3d(0.0, 0.05, 0.0);
  const double r_proj = rmsDifference(projected, truth, train);
  const double r_fit = rmsDifference(fitted, truth, train);
  Eigen::MatrixXd y(static_cast<Eigen::Index>(train.size()) * nominal.numJoints(), 4 * nominal.numJoints());
  for (std::size_t k = 0; k < train.size(); ++k) {
    y.middleRows(static_cast<Eigen::Index>(k) * nominal.numJoints(), nominal.numJoints()) =
        gravityRegressor(nominal, train[k]);
  }
  const double w = bounds.tie_weight * (y.transpose() * y / static_cast<double>(y.rows())).diagonal().maxCoeff();
  const double pull = (gravityParameters(projected) - gravityParameters(nominal)).squaredNorm();
  const double bound = std::sqrt(r_proj * r_proj + w * pull);
  std::printf("RMS residual: consistent fit %.4g N m, projected truth %.4g N m, bound %.4g N m\n", r_fit, r_proj,
              bound);
  EXPECT_LE(r_fit, bound * (1.0 + 1e-6) + 1e-9);
  EXPECT_GT(r_proj, 0.01);  // the bound is not trivially met: the projection costs torque
}

}  // namespace
}  // namespace fullarm::identification
