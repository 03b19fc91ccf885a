// The brace-posture search on a scene built around the arm: a bar placed under the forearm at
// a posture of the arm's self-motion near the start (the hand on its target). The search must
// find a braced posture that pushes at least 20 % harder than the arm can at the start, keep
// the hand on the target, stay within its budget and repeat itself for a seed.

#include "fullarm/accessibility/brace_search.hpp"

#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <numbers>
#include <array>
#include <limits>
#include <memory>
#include <sstream>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/query.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::accessibility {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;

/// The start: the hand in front of the shoulder, the forearm reaching forward and slightly down.
Eigen::VectorXd startPosture(const arm::ArmModel& model) {
  Eigen::VectorXd q = model.defaultPosture();
  q[model.jointIndex("R_SFE")] = 0.9;
  q[model.jointIndex("R_SAA")] = -0.4;
  q[model.jointIndex("R_HR")] = 0.2;
  q[model.jointIndex("R_EB")] = 1.2;
  q[model.jointIndex("R_WR")] = 0.0;
  q[model.jointIndex("R_WFE")] = 0.0;
  q[model.jointIndex("R_WAA")] = 0.0;
  return q;
}

/// Walks `distance_rad` along the self-motion of the hand pose from q (the test's own walk: small
/// null-space steps, each followed by Newton steps back onto the pose).
Eigen::VectorXd selfMotion(const arm::ArmModel& model, Eigen::VectorXd q, double distance_rad) {
  arm::ArmData fk(model);
  arm::computeForwardKinematics(model, fk, q);
  const Eigen::Isometry3d target = fk.X_WT;
  const int n = model.numArmJoints();
  const int steps = 100;
  Eigen::VectorXd previous;
  for (int i = 0; i < steps; ++i) {
    arm::computeForwardKinematics(model, fk, q);
    arm::PointJacobian J;
    arm::computePointJacobian(model, fk, model.tool_link, fk.X_WT.translation(), J);
    const Eigen::MatrixXd Ja = J.leftCols(n);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(Ja, Eigen::ComputeFullV);
    Eigen::VectorXd v = svd.matrixV().col(n - 1);
    if (previous.size() == 0) {
      if (distance_rad < 0.0) v = -v;
    } else if (v.dot(previous) < 0.0) {
      v = -v;
    }
    previous = v;
    q.head(n) += (std::abs(distance_rad) / steps) * v;
    for (int it = 0; it < 20; ++it) {
      arm::computeForwardKinematics(model, fk, q);
      Eigen::Matrix<double, 6, 1> e;
      e.head<3>() = target.translation() - fk.X_WT.translation();
      const Eigen::AngleAxisd aa(target.linear() * fk.X_WT.linear().transpose());
      e.tail<3>() = aa.angle() * aa.axis();
      arm::computePointJacobian(model, fk, model.tool_link, fk.X_WT.translation(), J);
      const Eigen::MatrixXd Jn = J.leftCols(n);
      q.head(n) += Jn.transpose() * (Jn * Jn.transpose()).ldlt().solve(e);
    }
  }
  return q;
}

/// The forearm's link point a fraction `along` of the way from the elbow to the wrist, world.
Eigen::Vector3d forearmPoint(const arm::ArmModel& model, const arm::ArmData& fk, double along) {
  const double d = model.joints[static_cast<std::size_t>(model.forearm_joint)].dh->d_m;
  return arm::pointInWorld(fk, model.forearm_joint, Eigen::Vector3d(0.0, 0.0, -d * (1.0 - along)));
}

/// A scene with one bar (a 0.5 m long box of 30 mm section), its top `top_z_W` in the arm's
/// world frame, centred under `p_W`, its long axis horizontal and across `forearm_W`.
std::string barScene(const Eigen::Vector3d& p_W, double top_z_W, const Eigen::Vector3d& forearm_W) {
  // Scene frame S = arm world frame W shifted: armBasePose puts DH frame 0 on the shoulder.
  const Eigen::Vector3d across = Eigen::Vector3d::UnitZ().cross(forearm_W).normalized();
  const double yaw_deg = std::atan2(across.y(), across.x()) * kRadToDeg;
  std::ostringstream s;
  s.precision(17);
  s << "schema_version: 1\nname: brace_bar\narm:\n  shoulder_m: [0.0, 0.0, 1.4]\nobjects:\n"
    << "  - name: bar\n    pose: {translation_m: [" << p_W.x() << ", " << p_W.y() << ", " << top_z_W - 0.015
    << "], rpy_deg: [0.0, 0.0, " << yaw_deg << "]}\n"
    << "    shape: {type: box, size_m: [0.5, 0.03, 0.03], max_edge_m: 0.02}\n";
  return s.str();
}

struct BarFixture {
  haptics::Scene scene;
  std::unique_ptr<haptics::CollisionWorld> world;
};

/// The bar scene in the arm world frame: parsed, then shifted by the scene's own X_SW.
BarFixture makeBar(const arm::ArmModel& model, const Eigen::Vector3d& p_W, double top_z_W,
                   const Eigen::Vector3d& forearm_W) {
  // First parse to learn X_SW (depends only on the arm block), then place the bar in S.
  const haptics::Scene probe = haptics::parseScene(barScene(p_W, top_z_W, forearm_W), "brace_bar.yaml");
  const Eigen::Isometry3d X_SW = haptics::armBasePose(probe, model);
  const Eigen::Vector3d p_S = X_SW * p_W;
  const Eigen::Vector3d forearm_S = X_SW.linear() * forearm_W;
  const double top_z_S = (X_SW * Eigen::Vector3d(p_W.x(), p_W.y(), top_z_W)).z();
  BarFixture f;
  f.scene = haptics::parseScene(barScene(p_S, top_z_S, forearm_S), "brace_bar.yaml");
  f.world = std::make_unique<haptics::CollisionWorld>(haptics::makeCollisionWorld(f.scene, model));
  return f;
}

/// Smallest distance of `link` (-1: any link) to the scene at q (cutoff 0.1 m).
double linkDistance(const arm::ArmModel& model, const haptics::CollisionWorld& world, const Eigen::VectorXd& q,
                    int link) {
  const std::unique_ptr<haptics::GlobalSearch> search = haptics::makeGlobalSearch(haptics::SearchKind::kSnch, world);
  haptics::HapticsParams params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  params.cutoff_m = 0.1;
  const std::array<haptics::RenderMode, 1> modes{haptics::RenderMode::kFullArm};
  const haptics::QueryResult r = haptics::renderQuery(model, world, *search, params, q, modes);
  double d = std::numeric_limits<double>::infinity();
  for (const haptics::LocalMinimum& m : r.minima) {
    if (link < 0 || m.link == link) d = std::min(d, m.distance_m);
  }
  return d;
}

TEST(BraceSearch, FindsABracePostureOnABarUnderTheForearm) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const HumanArm human = loadHumanArm(defaultHumanArmPath(), model);
  const haptics::HapticsParams params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  const Eigen::VectorXd q0 = startPosture(model);

  // The brace posture the bar is built for: 0.6 rad along the self-motion, where the elbow sits
  // about 19 mm lower than at the start. The bar goes under the forearm 15 % of the way from the
  // elbow, 4 mm below it (inside the rendered skin d_f = 10 mm: a light contact).
  constexpr double kGap_m = 0.004;
  const Eigen::VectorXd q_brace = selfMotion(model, q0, -0.6);
  arm::ArmData fk(model);
  arm::computeForwardKinematics(model, fk, q_brace);
  const Eigen::Vector3d p_W = forearmPoint(model, fk, 0.15);
  Eigen::Vector3d forearm_W = forearmPoint(model, fk, 1.0) - forearmPoint(model, fk, 0.0);
  forearm_W.z() = 0.0;
  double top_z = p_W.z() - 0.04 - 0.03;  // 0.04 m: the forearm capsule's radius; 0.03 m: well clear
  BarFixture bar = makeBar(model, p_W, top_z, forearm_W);
  // The forearm slopes and may meet the bar's edge: raise the bar until the measured gap is kGap_m.
  for (int i = 0; i < 8; ++i) {
    top_z += linkDistance(model, *bar.world, q_brace, model.forearm_joint) - kGap_m;
    bar = makeBar(model, p_W, top_z, forearm_W);
  }
  ASSERT_NEAR(linkDistance(model, *bar.world, q_brace, model.forearm_joint), kGap_m, 1e-5);
  ASSERT_GT(linkDistance(model, *bar.world, q0, -1), params.force_threshold_m);  // no contact at the start

  // Push along the hand's axis (wrist centre to hand point): the line the wrist can carry.
  arm::computeForwardKinematics(model, fk, q0);
  const Eigen::Isometry3d X_WT_target = fk.X_WT;
  const Eigen::Vector3d push = (fk.X_WT.translation() - forearmPoint(model, fk, 1.0)).normalized();

  BraceSearchOptions options;
  options.max_evaluations = 60;
  options.seed = 3;
  const std::unique_ptr<haptics::GlobalSearch> search = haptics::makeGlobalSearch(haptics::SearchKind::kSnch, *bar.world);
  const BraceSearchResult r = searchBracePosture(model, human, *bar.world, *search, params, q0, push, options);

  ASSERT_EQ(r.start.unbraced.status, ForceStatus::kOptimal) << r.start.unbraced.message;
  EXPECT_TRUE(r.start.contacts.empty());
  ASSERT_EQ(r.best.braced.status, ForceStatus::kOptimal) << r.best.braced.message;
  EXPECT_FALSE(r.best.contacts.empty());
  const double gain = r.bestPush() / r.start.unbraced.push_n;
  EXPECT_GE(gain, 1.2) << "start " << r.start.unbraced.push_n << " N, best " << r.bestPush() << " N";
  EXPECT_GE(r.bestPush(), 1.2 * r.best.unbraced.push_n);  // the gain is the bracing's, not the posture's
  EXPECT_LE(r.evaluations, options.max_evaluations);
  RecordProperty("start_push_n", std::to_string(r.start.unbraced.push_n));
  RecordProperty("best_braced_push_n", std::to_string(r.bestPush()));
  RecordProperty("best_unbraced_push_n", std::to_string(r.best.unbraced.push_n));
  RecordProperty("evaluations", r.evaluations);

  // The hand stays on the target, within the joint limits, with an allowed contact.
  arm::computeForwardKinematics(model, fk, r.q_best_rad);
  EXPECT_LE((fk.X_WT.translation() - X_WT_target.translation()).norm(), options.hand_position_tolerance_m);
  EXPECT_LE(Eigen::AngleAxisd(fk.X_WT.linear().transpose() * X_WT_target.linear()).angle(),
            options.hand_orientation_tolerance_rad);
  EXPECT_LE(r.max_hand_error_m, options.hand_position_tolerance_m);
  for (int j = 0; j < model.numJoints(); ++j) {
    EXPECT_GE(r.q_best_rad[j], model.joints[static_cast<std::size_t>(j)].limits.min_rad) << j;
    EXPECT_LE(r.q_best_rad[j], model.joints[static_cast<std::size_t>(j)].limits.max_rad) << j;
  }
  // The arm touches the bar there (forearm or the elbow's end of the upper arm), within delta.
  const double d_best = linkDistance(model, *bar.world, r.q_best_rad, -1);
  EXPECT_GE(d_best, params.force_threshold_m - options.penetration_max_m - 1e-12);
  EXPECT_LT(d_best, params.force_threshold_m);

  // The same seed gives the same posture.
  const BraceSearchResult again = searchBracePosture(model, human, *bar.world, *search, params, q0, push, options);
  EXPECT_EQ(again.evaluations, r.evaluations);
  EXPECT_EQ(again.q_best_rad, r.q_best_rad);
  EXPECT_EQ(again.bestPush(), r.bestPush());
}

TEST(BraceSearch, RejectsABadStart) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const HumanArm human = loadHumanArm(defaultHumanArmPath(), model);
  const haptics::HapticsParams params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  arm::ArmData fk(model);
  arm::computeForwardKinematics(model, fk, startPosture(model));
  BarFixture bar = makeBar(model, Eigen::Vector3d(0.3, 0.3, 0.0), -0.2, Eigen::Vector3d::UnitY());
  const std::unique_ptr<haptics::GlobalSearch> search = haptics::makeGlobalSearch(haptics::SearchKind::kSnch, *bar.world);
  Eigen::VectorXd q = startPosture(model);
  q[model.jointIndex("R_EB")] = 3.0;  // beyond the elbow's range
  EXPECT_THROW((void)searchBracePosture(model, human, *bar.world, *search, params, q, Eigen::Vector3d::UnitY()),
               std::invalid_argument);
  EXPECT_THROW((void)searchBracePosture(model, human, *bar.world, *search, params, q.head(3), Eigen::Vector3d::UnitY()),
               std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::accessibility
