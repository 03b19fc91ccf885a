// The spatial rigid-body dynamics on reduced arms (locked links merged into the active bodies)
// against the unreduced world-frame Newton-Euler oracle of world_frame_dynamics.hpp, and its
// analytic derivatives against central finite differences of that oracle.

#include <gtest/gtest.h>

#include <random>
#include <stdexcept>
#include <vector>

#include "alloc_guard.hpp"
#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/arm/rigid_body_dynamics.hpp"
#include "fullarm/arm/rigid_body_reduction.hpp"
#include "world_frame_dynamics.hpp"

namespace fullarm::arm {
namespace {

struct Sample {
  BodyVector q, qd, qdd;
};

Sample randomSample(int n, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Sample s;
  s.q.resize(n);
  s.qd.resize(n);
  s.qdd.resize(n);
  for (int k = 0; k < n; ++k) {
    s.q[k] = 1.2 * unit(rng);
    s.qd[k] = 3.0 * unit(rng);
    s.qdd[k] = 20.0 * unit(rng);
  }
  return s;
}

// World-frame inverse dynamics of the whole model (locked joints at the posture, at rest),
// read at the active joints.
BodyVector armInverseDynamics(const ArmModel& model, const std::vector<int>& active, const Eigen::VectorXd& posture,
                              const BodyVector& q, const BodyVector& qd, const BodyVector& qdd) {
  Eigen::VectorXd q_full = posture;
  Eigen::VectorXd qd_full = Eigen::VectorXd::Zero(model.numJoints());
  Eigen::VectorXd qdd_full = Eigen::VectorXd::Zero(model.numJoints());
  for (std::size_t k = 0; k < active.size(); ++k) {
    q_full[active[k]] = q[static_cast<Eigen::Index>(k)];
    qd_full[active[k]] = qd[static_cast<Eigen::Index>(k)];
    qdd_full[active[k]] = qdd[static_cast<Eigen::Index>(k)];
  }
  const Eigen::VectorXd tau_full = test::worldFrameInverseDynamics(model, q_full, qd_full, qdd_full);
  BodyVector tau(static_cast<Eigen::Index>(active.size()));
  for (std::size_t k = 0; k < active.size(); ++k) tau[static_cast<Eigen::Index>(k)] = tau_full[active[k]];
  return tau;
}

// Active sets: the seven arm joints (hand locked and merged into the wrist), a partial arm
// with locked arm joints between active ones, listed out of tree order, and one joint.
std::vector<std::vector<int>> activeSets(const ArmModel& model) {
  std::vector<int> arm7;
  for (int i = 0; i < model.numArmJoints(); ++i) arm7.push_back(i);
  return {arm7, {5, 0, 3}, {3}};
}

// Posture: the default, with the hand joints moved off zero so their merge is not trivial.
Eigen::VectorXd testPosture(const ArmModel& model) {
  Eigen::VectorXd posture = model.defaultPosture();
  for (int i = model.numArmJoints(); i < model.numJoints(); ++i)
    posture[i] = 0.5 * (model.joints[static_cast<std::size_t>(i)].limits.min_rad +
                        model.joints[static_cast<std::size_t>(i)].limits.max_rad) +
                 0.01;
  return posture;
}

TEST(RigidBodyDynamics, InverseDynamicsAndMassMatrixMatchUnreducedArm) {
  const ArmModel& model = test::defaultModel();
  ASSERT_GT(model.numJoints(), model.numArmJoints());  // the hand links exist and get merged
  const Eigen::VectorXd posture = testPosture(model);
  ArmData arm_data(model);
  std::mt19937 rng(11);
  for (const std::vector<int>& active : activeSets(model)) {
    const RigidBodyModel reduced = reduceArmModel(model, active, posture);
    const int n = reduced.tree.n;
    ASSERT_EQ(n, static_cast<int>(active.size()));
    RigidBodyData data;
    for (int trial = 0; trial < 10; ++trial) {
      const Sample s = randomSample(n, rng);
      computeRigidBodyKinematics(reduced, data, s.q, s.qd);
      BodyVector tau;
      computeRigidBodyInverseDynamics(reduced.tree, data, s.qdd, tau);
      const BodyVector expected = armInverseDynamics(model, active, posture, s.q, s.qd, s.qdd);
      EXPECT_LE((tau - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff())
          << "n = " << n << "\n"
          << tau.transpose() << "\n"
          << expected.transpose();
      // Mass matrix: the active sub-block of the unreduced arm's M (locked joints do not move).
      BodyMatrix mass;
      computeRigidBodyMassMatrix(reduced.tree, data, mass);
      Eigen::VectorXd q_full = posture;
      for (int k = 0; k < n; ++k) q_full[active[static_cast<std::size_t>(k)]] = s.q[k];
      const Eigen::MatrixXd full_mass = test::worldFrameMassMatrix(model, q_full);
      double worst = 0.0;
      for (int a = 0; a < n; ++a) {
        for (int b = 0; b < n; ++b) {
          worst = std::max(worst, std::abs(mass(a, b) - full_mass(active[static_cast<std::size_t>(a)],
                                                                  active[static_cast<std::size_t>(b)])));
        }
      }
      EXPECT_LE(worst, 1e-12 * mass.cwiseAbs().maxCoeff()) << "n = " << n;
      // Body points: a hand-link point carried by the wrist body is where fullarm::arm puts it.
      const int hand_link = model.numJoints() - 1;
      const BodyPoint point = reducePoint(model, active, posture, hand_link, Eigen::Vector3d(0.01, 0.02, 0.03));
      computeForwardKinematics(model, arm_data, q_full);
      const Eigen::Vector3d expected_p = pointInWorld(arm_data, hand_link, Eigen::Vector3d(0.01, 0.02, 0.03));
      const Eigen::Vector3d p =
          point.body < 0 ? point.p_B : Eigen::Vector3d(bodyPointInWorld(data, point.body, point.p_B));
      EXPECT_LE((p - expected_p).norm(), 1e-14) << "n = " << n;
    }
  }
}

// d ID / d(q, qd) = central differences of the world-frame inverse dynamics (step 1e-6: truncation
// ~1e-12, rounding ~1e-10 relative).
TEST(RigidBodyDynamics, AnalyticDerivativesMatchCentralDifferencesOfArmInverseDynamics) {
  const ArmModel& model = test::defaultModel();
  const Eigen::VectorXd posture = testPosture(model);
  std::mt19937 rng(5);
  for (const std::vector<int>& active : activeSets(model)) {
    const RigidBodyModel reduced = reduceArmModel(model, active, posture);
    const int n = reduced.tree.n;
    RigidBodyData data;
    for (int trial = 0; trial < 8; ++trial) {
      const Sample s = randomSample(n, rng);
      computeRigidBodyKinematics(reduced, data, s.q, s.qd);
      BodyVector tau;
      BodyMatrix dq;
      BodyMatrix dqd;
      computeRigidBodyInverseDynamicsDerivatives(reduced.tree, data, s.qdd, tau, dq, dqd);
      BodyMatrix fd_q(n, n);
      BodyMatrix fd_qd(n, n);
      constexpr double h = 1e-6;
      for (int j = 0; j < n; ++j) {
        Sample plus = s;
        Sample minus = s;
        plus.q[j] += h;
        minus.q[j] -= h;
        fd_q.col(j) = (armInverseDynamics(model, active, posture, plus.q, plus.qd, plus.qdd) -
                       armInverseDynamics(model, active, posture, minus.q, minus.qd, minus.qdd)) /
                      (2.0 * h);
        plus = minus = s;
        plus.qd[j] += h;
        minus.qd[j] -= h;
        fd_qd.col(j) = (armInverseDynamics(model, active, posture, plus.q, plus.qd, plus.qdd) -
                        armInverseDynamics(model, active, posture, minus.q, minus.qd, minus.qdd)) /
                       (2.0 * h);
      }
      // One scale for both (one joint turning about a fixed axis has d ID / d qd = 0 exactly).
      const double scale = fd_q.cwiseAbs().maxCoeff() + fd_qd.cwiseAbs().maxCoeff();
      EXPECT_LE((dq - fd_q).cwiseAbs().maxCoeff(), 1e-7 * scale) << "n = " << n << "\nanalytic\n"
                                                                 << dq << "\nfd\n"
                                                                 << fd_q;
      EXPECT_LE((dqd - fd_qd).cwiseAbs().maxCoeff(), 1e-7 * scale) << "n = " << n << "\nanalytic\n"
                                                                   << dqd << "\nfd\n"
                                                                   << fd_qd;
      // The pass also returns the inverse dynamics itself.
      const BodyVector expected = armInverseDynamics(model, active, posture, s.q, s.qd, s.qdd);
      EXPECT_LE((tau - expected).cwiseAbs().maxCoeff(), 1e-12 * expected.cwiseAbs().maxCoeff());
    }
  }
}

// The composite-subtree form (R13, one dot product per entry) = the body-by-body derivatives
// (R6-R8, O(n^2) spatial operations; the form the central-difference test above also checks) to
// 1e-9 relative, on every active set, with random states.
TEST(RigidBodyDynamics, CompositeDerivativesEqualBodyByBodyDerivatives) {
  const ArmModel& model = test::defaultModel();
  const Eigen::VectorXd posture = testPosture(model);
  std::mt19937 rng(11);
  for (const std::vector<int>& active : activeSets(model)) {
    const RigidBodyModel reduced = reduceArmModel(model, active, posture);
    const int n = reduced.tree.n;
    RigidBodyData data;
    for (int trial = 0; trial < 20; ++trial) {
      const Sample s = randomSample(n, rng);
      computeRigidBodyKinematics(reduced, data, s.q, s.qd);
      BodyVector tau;
      BodyVector tau_ref;
      BodyMatrix dq, dqd, dq_ref, dqd_ref;
      computeRigidBodyInverseDynamicsDerivatives(reduced.tree, data, s.qdd, tau, dq, dqd);
      computeRigidBodyInverseDynamicsDerivativesPerBody(reduced.tree, data, s.qdd, tau_ref, dq_ref, dqd_ref);
      const double scale = dq_ref.cwiseAbs().maxCoeff() + dqd_ref.cwiseAbs().maxCoeff();
      ASSERT_GT(scale, 0.0);
      EXPECT_LE((dq - dq_ref).cwiseAbs().maxCoeff(), 1e-9 * scale) << "n = " << n << "\ncomposite\n"
                                                                   << dq << "\nper body\n"
                                                                   << dq_ref;
      EXPECT_LE((dqd - dqd_ref).cwiseAbs().maxCoeff(), 1e-9 * scale) << "n = " << n << "\ncomposite\n"
                                                                     << dqd << "\nper body\n"
                                                                     << dqd_ref;
      EXPECT_EQ(tau, tau_ref);
    }
  }
}

TEST(RigidBodyDynamics, ComputeFunctionsDoNotAllocate) {
  const ArmModel& model = test::defaultModel();
  const RigidBodyModel reduced = reduceArmModel(model, activeSets(model)[0], model.defaultPosture());
  RigidBodyData data;
  std::mt19937 rng(2);
  const Sample s = randomSample(reduced.tree.n, rng);
  BodyVector tau(reduced.tree.n);
  BodyMatrix mass(reduced.tree.n, reduced.tree.n);
  BodyMatrix dq(reduced.tree.n, reduced.tree.n);
  BodyMatrix dqd(reduced.tree.n, reduced.tree.n);
  EXPECT_NO_HEAP_ALLOCATION(computeRigidBodyKinematics(reduced, data, s.q, s.qd));
  EXPECT_NO_HEAP_ALLOCATION(computeRigidBodyInverseDynamics(reduced.tree, data, s.qdd, tau));
  EXPECT_NO_HEAP_ALLOCATION(computeRigidBodyMassMatrix(reduced.tree, data, mass));
  EXPECT_NO_HEAP_ALLOCATION(computeRigidBodyInverseDynamicsDerivatives(reduced.tree, data, s.qdd, tau, dq, dqd));
  EXPECT_NO_HEAP_ALLOCATION(computeRigidBodyInverseDynamicsDerivativesPerBody(reduced.tree, data, s.qdd, tau, dq, dqd));
}

TEST(RigidBodyDynamics, RejectsBadActiveSets) {
  const ArmModel& model = test::defaultModel();
  const Eigen::VectorXd posture = model.defaultPosture();
  EXPECT_THROW((void)reduceArmModel(model, {}, posture), std::invalid_argument);
  EXPECT_THROW((void)reduceArmModel(model, {1, 1}, posture), std::invalid_argument);
  EXPECT_THROW((void)reduceArmModel(model, {model.numJoints()}, posture), std::invalid_argument);
  EXPECT_THROW((void)reduceArmModel(model, {0}, Eigen::VectorXd::Zero(2)), std::invalid_argument);
  EXPECT_THROW((void)reducePoint(model, {0}, posture, -1, Eigen::Vector3d::Zero()), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::arm
