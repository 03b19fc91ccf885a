// The single-axis load (one joint turning, the rest of the arm locked) that the plant's one-joint
// mode and the offline controller design use, against the full model: g_i(q) as q_i varies is
// a cos q_i + b sin q_i with a, b taken at q_i = 0 and pi/2, and M_ii does not depend on q_i.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"

namespace fullarm::arm {
namespace {

constexpr double kRelTol = 1e-12;
constexpr int kAngles = 25;  // q_i samples over [-pi, pi]

// Every joint of the model at `posture`: the single-axis coefficients reproduce the full model's
// g_i and M_ii at every sampled q_i.
void expectSingleAxisMatchesFullModel(const ArmModel& model, const Eigen::VectorXd& posture) {
  ArmData data(model);
  for (int i = 0; i < model.numJoints(); ++i) {
    const SingleAxisLoad load = computeSingleAxisLoad(model, i, posture);
    const double g_scale = std::max({std::abs(load.gravity_cos_nm), std::abs(load.gravity_sin_nm), 1e-3});
    ASSERT_GT(load.inertia_kgm2, 0.0) << model.joints[static_cast<std::size_t>(i)].name;
    Eigen::VectorXd q = posture;
    for (int k = 0; k < kAngles; ++k) {
      const double qi = -M_PI + 2.0 * M_PI * k / (kAngles - 1);
      q[i] = qi;
      computeGravityTorques(model, data, q);
      const double expected = load.gravity_cos_nm * std::cos(qi) + load.gravity_sin_nm * std::sin(qi);
      EXPECT_LE(std::abs(data.tau_gravity[i] - expected), kRelTol * g_scale)
          << model.joints[static_cast<std::size_t>(i)].name << " at q_i = " << qi;
      computeMassMatrix(model, data, q);
      EXPECT_LE(std::abs(data.mass_matrix(i, i) - load.inertia_kgm2), kRelTol * load.inertia_kgm2)
          << model.joints[static_cast<std::size_t>(i)].name << " at q_i = " << qi;
    }
  }
}

TEST(SingleAxisLoad, EqualsFullModelAtTheDefaultPosture) {
  const ArmModel& model = test::defaultModel();
  expectSingleAxisMatchesFullModel(model, model.defaultPosture());
}

TEST(SingleAxisLoad, EqualsFullModelAtRandomPostures) {
  const ArmModel& model = test::defaultModel();
  std::mt19937 rng(17);
  for (int trial = 0; trial < 5; ++trial) expectSingleAxisMatchesFullModel(model, test::randomConfiguration(model, rng));
}

// The gravity coefficients are not trivially zero on the shoulder at the default posture (the
// checks above would hold for a massless arm).
TEST(SingleAxisLoad, ShoulderCarriesTheArm) {
  const ArmModel& model = test::defaultModel();
  const SingleAxisLoad load = computeSingleAxisLoad(model, 1, model.defaultPosture());
  EXPECT_GT(std::hypot(load.gravity_cos_nm, load.gravity_sin_nm), 1.0);
}

TEST(SingleAxisLoad, RejectsBadJointOrPosture) {
  const ArmModel& model = test::defaultModel();
  EXPECT_THROW((void)computeSingleAxisLoad(model, -1, model.defaultPosture()), std::invalid_argument);
  EXPECT_THROW((void)computeSingleAxisLoad(model, model.numJoints(), model.defaultPosture()), std::invalid_argument);
  EXPECT_THROW((void)computeSingleAxisLoad(model, 0, Eigen::VectorXd::Zero(2)), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::arm
