// Gravity base parameters against the arm's own gravity (arm::computeGravityTorques): the
// regressor reproduces g(q) of the default model, and noise-free holds of a perturbed model give
// its base parameters within 1 % and its torques at held-out postures.

#include "fullarm/identification/gravity.hpp"

#include <gtest/gtest.h>

#include <cmath>

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

}  // namespace
}  // namespace fullarm::identification
