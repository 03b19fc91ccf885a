// One haptic query (renderQuery) on the shipped valve scene: the rendered contact torques equal
// J_c^T f summed over the minima with fullarm::arm's point Jacobians, the per-link forces equal
// the sum of the minima's forces on each link, the spring law per minimum, gravity computed apart
// from the contact torques, hand-only against full-arm on one search, and bad input.

#include "fullarm/haptics/query.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <stdexcept>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::haptics {
namespace {

using Eigen::Vector3d;

// Sums of a few products of forces of ~10 N and lever arms of ~0.5 m [N m].
constexpr double kTorqueTolerance_nm = 1e-11;
constexpr double kForceTolerance_n = 1e-12;

const Scene& valveScene() {
  static const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  return scene;
}

const CollisionWorld& valveWorld() {
  static const CollisionWorld world = makeCollisionWorld(valveScene(), arm::test::defaultModel());
  return world;
}

// reach_valve, a posture near it with deeper contacts, and one where the wrist links penetrate
// the truss (19 minima).
std::vector<Eigen::VectorXd> postures(const arm::ArmModel& model) {
  const Eigen::VectorXd reach = scenePosture(valveScene(), "reach_valve", model);
  Eigen::VectorXd deeper = reach;
  deeper[0] = 1.19;
  deeper[3] = 0.68;
  deeper[6] = 0.1;
  Eigen::VectorXd penetrating = reach;
  penetrating.head<7>() << 0.9, -0.2, 0.1, 1.0, 0.2, 0.1, 0.0;
  return {reach, deeper, penetrating};
}

constexpr RenderMode kBothModes[] = {RenderMode::kFullArm, RenderMode::kHandOnly};

TEST(HapticQuery, ContactTorquesEqualPointJacobianTransposeOfTheMinimaForces) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const HapticsParams params;
  SnchGlobalSearch search;
  int rendered = 0;
  for (const Eigen::VectorXd& q : postures(model)) {
    const QueryResult query = renderQuery(model, valveWorld(), search, params, q, kBothModes);
    ASSERT_FALSE(query.minima.empty());
    ASSERT_EQ(query.renderings.size(), 2u);
    arm::ArmData fk(model);
    arm::computeForwardKinematics(model, fk, q);
    arm::PointJacobian J;
    for (const QueryRendering& x : query.renderings) {
      ASSERT_TRUE(x.contact.status.ok());
      Eigen::VectorXd tau = Eigen::VectorXd::Zero(model.numJoints());
      for (std::size_t i = 0; i < query.minima.size(); ++i) {
        const LocalMinimum& m = query.minima[i];
        const Vector3d p_W = fk.X_WL[static_cast<std::size_t>(m.link)] * m.p_L;
        arm::computePointJacobian(model, fk, m.link, p_W, J);
        tau += J.topRows<3>().transpose() * x.contact.f_W[i];
        rendered += x.contact.rendered[i];
      }
      for (int j = 0; j < model.numJoints(); ++j) {
        EXPECT_NEAR(x.tau_contact_nm[j], tau[j], kTorqueTolerance_nm) << "joint " << j;
      }
    }
  }
  EXPECT_GT(rendered, 6);  // the postures make several springs in each mode
}

TEST(HapticQuery, PerLinkForcesAreTheSumsOfTheMinimaForcesOnEachLink) {
  const arm::ArmModel& model = arm::test::defaultModel();
  SnchGlobalSearch search;
  for (const Eigen::VectorXd& q : postures(model)) {
    const QueryResult query = renderQuery(model, valveWorld(), search, HapticsParams{}, q, kBothModes);
    for (const QueryRendering& x : query.renderings) {
      std::vector<Vector3d> sum(static_cast<std::size_t>(model.numJoints()), Vector3d::Zero());
      for (std::size_t i = 0; i < query.minima.size(); ++i) {
        sum[static_cast<std::size_t>(query.minima[i].link)] += x.contact.f_W[i];
      }
      for (int l = 0; l < model.numJoints(); ++l) {
        const auto k = static_cast<std::size_t>(l);
        EXPECT_LE((x.contact.link_force_W[k] - sum[k]).norm(), kForceTolerance_n) << "link " << l;
      }
    }
  }
}

TEST(HapticQuery, SpringsFollowTheSpringLawAndHandOnlyRendersOnlyTheHand) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const HapticsParams params;
  SnchGlobalSearch search;
  const Eigen::VectorXd q = scenePosture(valveScene(), "reach_valve", model);
  const QueryResult query = renderQuery(model, valveWorld(), search, params, q, kBothModes);
  const QueryRendering& full = query.renderings[0];
  const QueryRendering& hand = query.renderings[1];
  EXPECT_EQ(full.mode, RenderMode::kFullArm);
  EXPECT_EQ(hand.mode, RenderMode::kHandOnly);
  bool arm_contact = false;
  for (std::size_t i = 0; i < query.minima.size(); ++i) {
    const LocalMinimum& m = query.minima[i];
    EXPECT_LE(m.distance_m, params.cutoff_m);
    // One tick from rest: |f| = k (d_f - d) below d_f, along -u_W; nothing at or beyond d_f.
    const double magnitude =
        m.distance_m < params.force_threshold_m
            ? std::min(params.stiffness_npm * (params.force_threshold_m - m.distance_m), params.max_force_per_minimum_n)
            : 0.0;
    EXPECT_LE((full.contact.f_W[i] - (-magnitude * m.u_W)).norm(), kForceTolerance_n) << i;
    const bool hand_link = isHandLink(model, m.link);
    EXPECT_LE((hand.contact.f_W[i] - (hand_link ? full.contact.f_W[i] : Vector3d::Zero())).norm(), kForceTolerance_n)
        << i;
    arm_contact = arm_contact || (!hand_link && magnitude > 0.0);
  }
  EXPECT_TRUE(arm_contact);  // reach_valve touches the opening with a forearm link too
  EXPECT_GT(full.contact.active_springs, hand.contact.active_springs);
  // The contact records do not depend on the mode.
  for (std::size_t l = 0; l < full.contact.links.size(); ++l) {
    EXPECT_EQ(full.contact.links[l].in_contact, hand.contact.links[l].in_contact);
    EXPECT_EQ(full.contact.links[l].min_distance_m, hand.contact.links[l].min_distance_m);
  }
}

TEST(HapticQuery, GravityIsComputedApartAndTheTotalIsContactPlusGravity) {
  const arm::ArmModel& model = arm::test::defaultModel();
  SnchGlobalSearch search;
  const Eigen::VectorXd q = postures(model)[1];
  const QueryResult query = renderQuery(model, valveWorld(), search, HapticsParams{}, q, kBothModes);
  arm::ArmData data(model);
  arm::computeGravityTorques(model, data, q);
  EXPECT_EQ(query.tau_gravity_nm, data.tau_gravity);
  EXPECT_EQ(query.q_rad, q);
  for (const QueryRendering& x : query.renderings) {
    EXPECT_EQ(x.tau_total_nm, Eigen::VectorXd(x.tau_contact_nm + data.tau_gravity));
    EXPECT_GT(x.tau_contact_nm.norm(), 0.0);
  }
  arm::computeForwardKinematics(model, data, q);
  ASSERT_EQ(query.X_WL.size(), data.X_WL.size());
  for (std::size_t l = 0; l < data.X_WL.size(); ++l) EXPECT_TRUE(query.X_WL[l].isApprox(data.X_WL[l], 0.0));
  EXPECT_EQ(query.search, "snch");
  EXPECT_FALSE(query.fault());
}

TEST(HapticQuery, BulletSearchGivesTheSameMinimaAndBadInputIsRejected) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Eigen::VectorXd q = scenePosture(valveScene(), "reach_valve", model);
  const std::unique_ptr<GlobalSearch> snch = makeGlobalSearch(SearchKind::kSnch, valveWorld());
  const std::unique_ptr<GlobalSearch> bullet = makeGlobalSearch(SearchKind::kBullet, valveWorld());
  const RenderMode full[] = {RenderMode::kFullArm};
  const QueryResult a = renderQuery(model, valveWorld(), *snch, HapticsParams{}, q, full);
  const QueryResult b = renderQuery(model, valveWorld(), *bullet, HapticsParams{}, q, full);
  EXPECT_EQ(a.search, "snch");
  EXPECT_EQ(b.search, "bullet");
  ASSERT_EQ(a.minima.size(), b.minima.size());
  for (std::size_t i = 0; i < a.minima.size(); ++i) {
    EXPECT_TRUE(sameFeaturePair(a.minima[i], b.minima[i])) << i;
    EXPECT_NEAR(a.minima[i].distance_m, b.minima[i].distance_m, 1e-12) << i;
  }
  EXPECT_THROW((void)renderQuery(model, valveWorld(), *snch, HapticsParams{}, Eigen::VectorXd::Zero(3), full),
               std::invalid_argument);
  EXPECT_THROW((void)renderQuery(model, valveWorld(), *snch, HapticsParams{}, q, std::span<const RenderMode>()),
               std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::haptics
