// Rigid-body dynamics against orocos-kdl (an independent Newton-Euler and composite-inertia
// implementation), the world-frame Newton-Euler oracle of world_frame_dynamics.hpp, finite
// differences of the potential energy, and the structure of M qdd + C qd + g = tau.

#include "fullarm/arm/dynamics.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <kdl/chaindynparam.hpp>
#include <kdl/treeidsolver_recursive_newton_euler.hpp>
#include <random>

#include "arm_test_util.hpp"
#include "fullarm/arm/kdl_conversion.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "matrix_compare.hpp"
#include "world_frame_dynamics.hpp"

namespace fullarm::arm {
namespace {

using fullarm::testing::Tolerance;

constexpr int kRandomStates = 100;
constexpr unsigned kSeed = 7;
constexpr double kVelocityScale_radps = 2.0;
constexpr double kAccelScale_radps2 = 5.0;

KDL::JntArray toKdl(const Eigen::VectorXd& v, const Eigen::VectorXi& index, unsigned n) {
  KDL::JntArray a(n);
  for (int i = 0; i < v.size(); ++i) a(static_cast<unsigned>(index[i])) = v[i];
  return a;
}

KDL::Vector gravityOf(const ArmModel& model) {
  return KDL::Vector(model.gravity_W_mps2.x(), model.gravity_W_mps2.y(), model.gravity_W_mps2.z());
}

TEST(Dynamics, InverseDynamicsMatchesKdlTreeNewtonEuler) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  const KDL::Tree tree = toKdlTree(model);
  KDL::TreeIdSolver_RNE solver(tree, gravityOf(model));
  const Eigen::VectorXi index = test::kdlJointIndices(model, tree);
  const unsigned nk = tree.getNrOfJoints();
  std::mt19937 rng(kSeed);
  double worst = 0.0;
  for (int trial = 0; trial < kRandomStates; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    const Eigen::VectorXd qd = test::randomVector(model.numJoints(), kVelocityScale_radps, rng);
    const Eigen::VectorXd qdd = test::randomVector(model.numJoints(), kAccelScale_radps2, rng);
    computeInverseDynamics(model, data, q, qd, qdd);
    KDL::JntArray tau_kdl(nk);
    KDL::WrenchMap no_wrenches;
    ASSERT_GE(solver.CartToJnt(toKdl(q, index, nk), toKdl(qd, index, nk), toKdl(qdd, index, nk), no_wrenches, tau_kdl),
              0);
    for (int i = 0; i < model.numJoints(); ++i) {
      worst = std::max(worst, std::abs(data.tau[i] - tau_kdl(static_cast<unsigned>(index[i]))));
    }
  }
  EXPECT_LE(worst, Tolerance::kExact);
}

TEST(Dynamics, MassCoriolisGravityMatchKdlChainDynParam) {
  const ArmModel& model = test::armOnlyModel();
  ArmData data(model);
  const KDL::Chain chain = toKdlChain(model, model.numJoints() - 1);
  ASSERT_EQ(chain.getNrOfJoints(), static_cast<unsigned>(model.numJoints()));
  KDL::ChainDynParam dyn(chain, gravityOf(model));
  const auto n = static_cast<unsigned>(model.numJoints());
  std::mt19937 rng(kSeed + 1);
  for (int trial = 0; trial < kRandomStates; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    const Eigen::VectorXd qd = test::randomVector(model.numJoints(), kVelocityScale_radps, rng);
    KDL::JntArray q_kdl(n);
    KDL::JntArray qd_kdl(n);
    q_kdl.data = q;
    qd_kdl.data = qd;
    KDL::JntSpaceInertiaMatrix M(n);
    KDL::JntArray C(n);
    KDL::JntArray G(n);
    ASSERT_GE(dyn.JntToMass(q_kdl, M), 0);
    ASSERT_GE(dyn.JntToCoriolis(q_kdl, qd_kdl, C), 0);
    ASSERT_GE(dyn.JntToGravity(q_kdl, G), 0);
    computeMassMatrix(model, data, q);
    ASSERT_MATRIX_NEAR(data.mass_matrix, M.data, Tolerance::kExact);
    computeCoriolisTorques(model, data, q, qd);
    ASSERT_MATRIX_NEAR(data.tau_coriolis, C.data, Tolerance::kExact);
    // KDL's JntToGravity returns the same sign convention: the torque that holds the arm.
    computeGravityTorques(model, data, q);
    ASSERT_MATRIX_NEAR(data.tau_gravity, G.data, Tolerance::kExact);
  }
}

// The library's spatial algorithm against the world-frame Newton-Euler of Craig (a second,
// independent implementation kept in the tests), on the whole tree with the hand.
TEST(Dynamics, SpatialAlgorithmMatchesWorldFrameNewtonEuler) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  std::mt19937 rng(kSeed + 8);
  double worst_tau = 0.0, worst_mass = 0.0, worst_c = 0.0, worst_g = 0.0;
  for (int trial = 0; trial < kRandomStates; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    const Eigen::VectorXd qd = test::randomVector(model.numJoints(), kVelocityScale_radps, rng);
    const Eigen::VectorXd qdd = test::randomVector(model.numJoints(), kAccelScale_radps2, rng);
    const Eigen::VectorXd tau = test::worldFrameInverseDynamics(model, q, qd, qdd);
    computeInverseDynamics(model, data, q, qd, qdd);
    worst_tau = std::max(worst_tau, (data.tau - tau).cwiseAbs().maxCoeff() / tau.cwiseAbs().maxCoeff());
    const Eigen::MatrixXd mass = test::worldFrameMassMatrix(model, q);
    computeMassMatrix(model, data, q);
    worst_mass = std::max(worst_mass, (data.mass_matrix - mass).cwiseAbs().maxCoeff() / mass.cwiseAbs().maxCoeff());
    const Eigen::VectorXd c = test::worldFrameCoriolisTorques(model, q, qd);
    computeCoriolisTorques(model, data, q, qd);
    worst_c = std::max(worst_c, (data.tau_coriolis - c).cwiseAbs().maxCoeff() / c.cwiseAbs().maxCoeff());
    const Eigen::VectorXd g = test::worldFrameGravityTorques(model, q);
    computeGravityTorques(model, data, q);
    worst_g = std::max(worst_g, (data.tau_gravity - g).cwiseAbs().maxCoeff() / g.cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst_tau, 1e-12);
  EXPECT_LE(worst_mass, 1e-12);
  EXPECT_LE(worst_c, 1e-12);
  EXPECT_LE(worst_g, 1e-12);
}

TEST(Dynamics, MassMatrixIsSymmetricPositiveDefinite) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  std::mt19937 rng(kSeed + 2);
  for (int trial = 0; trial < kRandomStates; ++trial) {
    computeMassMatrix(model, data, test::randomConfiguration(model, rng));
    ASSERT_MATRIX_NEAR(data.mass_matrix, data.mass_matrix.transpose(), Tolerance::kExact);
    const Eigen::LLT<Eigen::MatrixXd> llt(data.mass_matrix);
    ASSERT_EQ(llt.info(), Eigen::Success) << data.mass_matrix;
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(data.mass_matrix);
    EXPECT_GT(eig.eigenvalues().minCoeff(), 0.0);
  }
}

TEST(Dynamics, InverseDynamicsEqualsMassCoriolisPlusGravity) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  std::mt19937 rng(kSeed + 3);
  for (int trial = 0; trial < kRandomStates; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    const Eigen::VectorXd qd = test::randomVector(model.numJoints(), kVelocityScale_radps, rng);
    const Eigen::VectorXd qdd = test::randomVector(model.numJoints(), kAccelScale_radps2, rng);
    computeMassMatrix(model, data, q);
    const Eigen::MatrixXd M = data.mass_matrix;
    computeCoriolisTorques(model, data, q, qd);
    const Eigen::VectorXd c = data.tau_coriolis;
    computeGravityTorques(model, data, q);
    const Eigen::VectorXd g = data.tau_gravity;
    computeInverseDynamics(model, data, q, qd, qdd);
    ASSERT_MATRIX_NEAR(data.tau, M * qdd + c + g, Tolerance::kExact);
  }
}

TEST(Dynamics, GravityTorquesAreTheGradientOfPotentialEnergy) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  std::mt19937 rng(kSeed + 4);
  // V is O(10 J); central differences with h = 1e-5: truncation ~1e-10, round-off ~1e-10 N m.
  constexpr double kStep = 1e-5;
  constexpr double kTol = 1e-8;
  for (int trial = 0; trial < kRandomStates; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    Eigen::VectorXd grad(model.numJoints());
    for (int j = 0; j < model.numJoints(); ++j) {
      Eigen::VectorXd qp = q;
      Eigen::VectorXd qm = q;
      qp[j] += kStep;
      qm[j] -= kStep;
      grad[j] = (computePotentialEnergy(model, data, qp) - computePotentialEnergy(model, data, qm)) / (2 * kStep);
    }
    computeGravityTorques(model, data, q);
    ASSERT_MATRIX_NEAR(data.tau_gravity, grad, kTol);
  }
}

// Independent check of C: along any motion, dKE/dt = qd . (tau - g) with tau from inverse
// dynamics, i.e. qd . (M qdd + C qd) = d/dt (0.5 qd^T M qd). Differentiate KE numerically along
// q(t) = q0 + qd0 t + 0.5 qdd0 t^2.
TEST(Dynamics, PowerBalanceHoldsAlongRandomMotions) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  std::mt19937 rng(kSeed + 5);
  constexpr double kStep_s = 1e-5;
  constexpr double kTol_w = 1e-7;
  for (int trial = 0; trial < kRandomStates; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    const Eigen::VectorXd qd = test::randomVector(model.numJoints(), kVelocityScale_radps, rng);
    const Eigen::VectorXd qdd = test::randomVector(model.numJoints(), kAccelScale_radps2, rng);
    const auto ke = [&](double t) {
      return computeKineticEnergy(model, data, q + qd * t + 0.5 * qdd * t * t, qd + qdd * t);
    };
    const double dke = (ke(kStep_s) - ke(-kStep_s)) / (2 * kStep_s);
    computeInverseDynamics(model, data, q, qd, qdd);
    const Eigen::VectorXd tau = data.tau;
    computeGravityTorques(model, data, q);
    EXPECT_NEAR(qd.dot(tau - data.tau_gravity), dke, kTol_w);
  }
}

TEST(Dynamics, GravityTorquesEqualStaticInverseDynamics) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  std::mt19937 rng(kSeed + 6);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.numJoints());
  for (int trial = 0; trial < kRandomStates; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    computeInverseDynamics(model, data, q, zero, zero);
    computeGravityTorques(model, data, q);
    ASSERT_MATRIX_NEAR(data.tau, data.tau_gravity, Tolerance::kExact);
  }
}

// Gravity at the kinematics already in ArmData equals the convenience that runs them, and the
// pass counters count exactly the passes each function makes.
TEST(Dynamics, GravityAtKinematicsReusesTheKinematicsAndCountsPasses) {
  const ArmModel& model = test::defaultModel();
  ArmData data(model);
  ArmData reference(model);
  std::mt19937 rng(kSeed + 7);
  const Eigen::VectorXd q = test::randomConfiguration(model, rng);
  computeGravityTorques(model, reference, q);
  EXPECT_EQ(reference.forward_kinematics_passes, 1u);
  EXPECT_EQ(reference.gravity_passes, 1u);
  computeForwardKinematics(model, data, q);
  EXPECT_EQ(data.forward_kinematics_passes, 1u);
  EXPECT_EQ(data.gravity_passes, 0u);
  computeGravityTorquesAtKinematics(model, data);
  EXPECT_EQ(data.forward_kinematics_passes, 1u);
  EXPECT_EQ(data.gravity_passes, 1u);
  EXPECT_EQ(data.tau_gravity, reference.tau_gravity);
  // At other kinematics the result follows them, not a configuration of its own.
  const Eigen::VectorXd q2 = test::randomConfiguration(model, rng);
  computeForwardKinematics(model, data, q2);
  computeGravityTorquesAtKinematics(model, data);
  computeGravityTorques(model, reference, q2);
  EXPECT_EQ(data.tau_gravity, reference.tau_gravity);
  EXPECT_EQ(data.forward_kinematics_passes, 2u);
  EXPECT_EQ(data.gravity_passes, 2u);
}

// A single point mass on a horizontal lever: tau = m g r by hand.
TEST(Dynamics, SinglePendulumGravityMatchesHandCalculation) {
  ArmModel model;
  model.name = "pendulum";
  Joint j;
  j.name = "hinge";
  j.dh = DhParameters{M_PI / 2, 0.0, 0.0, 0.0};  // alpha = 90 deg: joint axis Rx(90 deg) z = -y
  j.X_PL0 = dhTransform(*j.dh);
  j.limits = {-3.0, 3.0, 1.0, 100.0};
  j.inertial.mass_kg = 2.0;
  j.inertial.com_m = {0.5, 0.0, 0.0};
  j.inertial.inertia_com_kgm2 = Eigen::Matrix3d::Identity() * 1e-3;  // small sphere: no gravity effect
  j.potentiometer = {2e-3, -2047.0, 1, 0.0, 12};                     // reads +-4.1 rad
  j.torque_sensor = {0.05, -2047.0, 12};
  j.torque_command = {0.05, -2047.0, 12};
  model.joints.push_back(j);
  model.tool_link = 0;
  validateArmModel(model);
  ArmData data(model);
  for (const double q : {0.0, 0.4, -1.1}) {
    computeGravityTorques(model, data, Eigen::VectorXd::Constant(1, q));
    // By hand: the joint axis is Rx(90 deg) z = -y, the lever Rx(90 deg) Rz(q) x = (cos q, 0, sin q),
    // so the COM height is 0.5 sin q, V = m g 0.5 sin q and g(q) = dV/dq = +m g 0.5 cos q.
    EXPECT_NEAR(data.tau_gravity[0], 2.0 * 9.81 * 0.5 * std::cos(q), 1e-12);
  }
}

}  // namespace
}  // namespace fullarm::arm
