// Forward kinematics and point Jacobians of the DTS master model, against the published SL
// poses (docs/dts-reference.md §2.3 and §2.5), orocos-kdl and finite differences.

#include "fullarm/arm/kinematics.hpp"

#include <gtest/gtest.h>

#include <kdl/jacobian.hpp>
#include <kdl/treefksolverpos_recursive.hpp>
#include <kdl/treejnttojacsolver.hpp>
#include <random>

#include "arm_test_util.hpp"
#include "fullarm/arm/kdl_conversion.hpp"
#include "matrix_compare.hpp"

namespace fullarm::arm {
namespace {

using fullarm::testing::Tolerance;
using test::defaultModel;

constexpr int kRandomConfigurations = 200;
constexpr unsigned kSeed = 20261121;

Eigen::Matrix3d rows(std::initializer_list<double> v) {
  Eigen::Matrix3d m;
  auto it = v.begin();
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m(r, c) = *it++;
  return m;
}

Eigen::VectorXd armConfiguration(const ArmModel& model, std::initializer_list<double> arm) {
  Eigen::VectorXd q = Eigen::VectorXd::Zero(model.numJoints());
  int i = 0;
  for (double v : arm) q[i++] = v;
  return q;
}

struct PublishedPose {
  std::initializer_list<double> q;
  Eigen::Vector3d p;
  Eigen::Matrix3d R;
};

// Reference section 2.5: hand-frame pose from SL's generated kinematics.
TEST(Kinematics, HandPoseMatchesPublishedSlPoses) {
  const ArmModel& model = defaultModel();
  ArmData data(model);
  const PublishedPose poses[] = {
      {{0, 0, 0, 0, 0, 0, 0}, {0.318443, -0.008100, -0.367257}, rows({1, 0, 0, 0, 0, 1, 0, -1, 0})},
      {{0, -0.3, 0, 1.57, 0, 0, 0},
       {0.404146, 0.363093, 0.011167},
       rows({0.955336, 0.000235, -0.295520, 0, 1, 0.000796, 0.295520, -0.000761, 0.955336})},
      {{0.3, -0.5, 0.4, 1.2, -0.6, 0.3, -0.2},
       {0.582262, 0.415577, 0.081544},
       rows({0.409476, 0.589377, -0.696394, -0.478802, 0.788580, 0.385863, 0.776581, 0.175433, 0.605099})},
  };
  for (const PublishedPose& pose : poses) {
    computeForwardKinematics(model, data, armConfiguration(model, pose.q));
    EXPECT_MATRIX_NEAR(data.X_WT.translation(), pose.p, Tolerance::kSixDecimals);
    EXPECT_MATRIX_NEAR(data.X_WT.linear(), pose.R, Tolerance::kSixDecimals);
  }
}

// Reference section 2.3: joint axes at q = 0, and each joint origin on its published axis line.
TEST(Kinematics, ZeroPoseJointAxesMatchPublishedAxes) {
  const ArmModel& model = defaultModel();
  ArmData data(model);
  computeForwardKinematics(model, data, Eigen::VectorXd::Zero(model.numJoints()));
  const double h = std::sqrt(0.5);
  const Eigen::Vector3d axes[] = {{h, 0, h},  {0, 1, 0}, {0, 0, -1}, {1, 0, 0}, {0, 0, -1},
                                  {0, -1, 0}, {1, 0, 0}, {0, 1, 0},  {1, 0, 0}, {1, 0, 0}};
  const Eigen::Vector3d points[] = {{0.282843, 0, 0.282843},        {0.282843, 0, 0.282843},
                                    {0.320943, 0, 0.282843},        {0.320943, 0, -0.004157},
                                    {0.318443, 0, -0.004157},       {0.318443, 0, -0.282257},
                                    {0.318443, -0.0081, -0.282257}, {0.268443, 0.0219, -0.282257},
                                    {0.268443, 0.0219, -0.282257},  {0.338443, 0.0219, -0.382257}};
  ASSERT_EQ(model.numJoints(), 10);
  for (int i = 0; i < 10; ++i) {
    const auto k = static_cast<std::size_t>(i);
    SCOPED_TRACE(model.joints[k].name);
    EXPECT_MATRIX_NEAR(data.z_W[k], axes[i], Tolerance::kSixDecimals);
    // The DH origin may sit elsewhere on the axis than SL's origin: test the line.
    EXPECT_MATRIX_NEAR((data.o_W[k] - points[i]).cross(axes[i]), Eigen::Vector3d::Zero(), Tolerance::kSixDecimals);
  }
}

// Reference section 2.3: thumb tip and finger tip at q = 0.
TEST(Kinematics, ThumbAndFingerTipsMatchPublishedPoints) {
  const ArmModel& model = defaultModel();
  ArmData data(model);
  computeForwardKinematics(model, data, Eigen::VectorXd::Zero(model.numJoints()));
  const int thumb = model.jointIndex("R_TV");
  const int finger = model.jointIndex("R_FAA");
  EXPECT_MATRIX_NEAR(pointInWorld(data, thumb, {0, 0.10, 0}), Eigen::Vector3d(0.268443, 0.0219, -0.382257),
                     Tolerance::kSixDecimals);
  EXPECT_MATRIX_NEAR(pointInWorld(data, finger, {0, 0.05, 0}), Eigen::Vector3d(0.338443, 0.0219, -0.432257),
                     Tolerance::kSixDecimals);
}

Eigen::Isometry3d fromKdl(const KDL::Frame& f) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) X.linear()(r, c) = f.M(static_cast<unsigned>(r), static_cast<unsigned>(c));
    X.translation()[r] = f.p(static_cast<unsigned>(r));
  }
  return X;
}

TEST(Kinematics, LinkFramesMatchKdlAtRandomConfigurations) {
  const ArmModel& model = defaultModel();
  ArmData data(model);
  const KDL::Tree tree = toKdlTree(model);
  KDL::TreeFkSolverPos_recursive fk(tree);
  const Eigen::VectorXi index = test::kdlJointIndices(model, tree);
  std::mt19937 rng(kSeed);
  double worst = 0.0;
  for (int trial = 0; trial < kRandomConfigurations; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    KDL::JntArray q_kdl(tree.getNrOfJoints());
    for (int i = 0; i < model.numJoints(); ++i) q_kdl(static_cast<unsigned>(index[i])) = q[i];
    computeForwardKinematics(model, data, q);
    for (int i = 0; i < model.numJoints(); ++i) {
      KDL::Frame f;
      ASSERT_GE(fk.JntToCart(q_kdl, f, model.joints[static_cast<std::size_t>(i)].name), 0);
      const Eigen::Isometry3d X = fromKdl(f);
      worst = std::max(worst, (X.matrix() - data.X_WL[static_cast<std::size_t>(i)].matrix()).cwiseAbs().maxCoeff());
    }
    KDL::Frame tool;
    ASSERT_GE(fk.JntToCart(q_kdl, tool, "tool"), 0);
    worst = std::max(worst, (fromKdl(tool).matrix() - data.X_WT.matrix()).cwiseAbs().maxCoeff());
  }
  EXPECT_LE(worst, Tolerance::kExact);
}

// A random point within 0.2 m of the link origin, fixed in the link frame.
Eigen::Vector3d randomLinkPoint(std::mt19937& rng) {
  return test::randomVector(3, 0.2, rng);
}

TEST(Kinematics, PointJacobianMatchesKdlAtRandomConfigurations) {
  const ArmModel& model = defaultModel();
  ArmData data(model);
  const KDL::Tree tree = toKdlTree(model);
  KDL::TreeJntToJacSolver jac_solver(tree);
  const Eigen::VectorXi index = test::kdlJointIndices(model, tree);
  std::mt19937 rng(kSeed + 1);
  std::uniform_int_distribution<int> pick_link(0, model.numJoints() - 1);
  PointJacobian J;
  double worst = 0.0;
  for (int trial = 0; trial < kRandomConfigurations; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    const int link = pick_link(rng);
    computeForwardKinematics(model, data, q);
    const Eigen::Vector3d p_W = pointInWorld(data, link, randomLinkPoint(rng));
    computePointJacobian(model, data, link, p_W, J);

    KDL::JntArray q_kdl(tree.getNrOfJoints());
    for (int i = 0; i < model.numJoints(); ++i) q_kdl(static_cast<unsigned>(index[i])) = q[i];
    KDL::Jacobian jac(tree.getNrOfJoints());
    ASSERT_GE(jac_solver.JntToJac(q_kdl, jac, model.joints[static_cast<std::size_t>(link)].name), 0);
    // KDL's reference point is the segment origin, in world coordinates; move it to p_W.
    const Eigen::Vector3d o = data.o_W[static_cast<std::size_t>(link)];
    jac.changeRefPoint(KDL::Vector(p_W.x() - o.x(), p_W.y() - o.y(), p_W.z() - o.z()));
    for (int i = 0; i < model.numJoints(); ++i) {
      for (int r = 0; r < 6; ++r) {
        worst = std::max(worst, std::abs(J(r, i) - jac(static_cast<unsigned>(r), static_cast<unsigned>(index[i]))));
      }
    }
  }
  EXPECT_LE(worst, Tolerance::kExact);
}

TEST(Kinematics, PointJacobianMatchesFiniteDifferences) {
  const ArmModel& model = defaultModel();
  ArmData data(model);
  ArmData probe(model);
  std::mt19937 rng(kSeed + 2);
  std::uniform_int_distribution<int> pick_link(0, model.numJoints() - 1);
  // Central differences: truncation h^2/6 |p'''| ~ 2e-11 m, round-off eps |p| / h ~ 1e-11 m.
  constexpr double kStep = 1e-5;
  PointJacobian J;
  double worst = 0.0;
  for (int trial = 0; trial < kRandomConfigurations; ++trial) {
    const Eigen::VectorXd q = test::randomConfiguration(model, rng);
    const int link = pick_link(rng);
    const Eigen::Vector3d p_L = randomLinkPoint(rng);
    computeForwardKinematics(model, data, q);
    computePointJacobian(model, data, link, pointInWorld(data, link, p_L), J);
    for (int j = 0; j < model.numJoints(); ++j) {
      Eigen::VectorXd qp = q;
      Eigen::VectorXd qm = q;
      qp[j] += kStep;
      qm[j] -= kStep;
      computeForwardKinematics(model, probe, qp);
      const Eigen::Vector3d pp = pointInWorld(probe, link, p_L);
      const Eigen::Matrix3d Rp = probe.X_WL[static_cast<std::size_t>(link)].linear();
      computeForwardKinematics(model, probe, qm);
      const Eigen::Vector3d pm = pointInWorld(probe, link, p_L);
      const Eigen::Matrix3d Rm = probe.X_WL[static_cast<std::size_t>(link)].linear();
      const Eigen::Vector3d v = (pp - pm) / (2 * kStep);
      // Angular velocity from the rotation increment R(q+h) R(q-h)^T = exp([w] 2h).
      const Eigen::AngleAxisd dR(Rp * Rm.transpose());
      const Eigen::Vector3d w = dR.axis() * dR.angle() / (2 * kStep);
      worst = std::max(worst, (J.block<3, 1>(0, j) - v).cwiseAbs().maxCoeff());
      worst = std::max(worst, (J.block<3, 1>(3, j) - w).cwiseAbs().maxCoeff());
    }
  }
  EXPECT_LE(worst, Tolerance::kExact);
}

TEST(Kinematics, JointMovesLinkFollowsTheTree) {
  const ArmModel& model = defaultModel();
  const int waa = model.jointIndex("R_WAA");
  const int tl = model.jointIndex("R_TL");
  const int tv = model.jointIndex("R_TV");
  const int faa = model.jointIndex("R_FAA");
  EXPECT_TRUE(jointMovesLink(model, 0, tv));
  EXPECT_TRUE(jointMovesLink(model, waa, faa));
  EXPECT_TRUE(jointMovesLink(model, tl, tv));
  EXPECT_FALSE(jointMovesLink(model, tl, faa));
  EXPECT_FALSE(jointMovesLink(model, faa, waa));
}

}  // namespace
}  // namespace fullarm::arm

namespace fullarm::arm {
namespace {

TEST(KdlConversion, ReservedSegmentNamesAreRefused) {
  ArmModel model = test::defaultModel();
  model.joints[1].name = "tool";
  EXPECT_THROW((void)toKdlTree(model), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::arm
