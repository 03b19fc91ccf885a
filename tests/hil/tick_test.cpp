// The tick: the pieces of the 1 kHz path composed in order (against the same pieces composed by
// hand), one kinematics and one gravity pass per tick, no allocation (adopting a set included),
// hand-only rendering with per-link records, the sweep bound against the link meshes' vertices,
// and the stale-minima fade.

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "alloc_guard.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/local_descent.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/hil/global_search.hpp"
#include "fullarm/hil/tick.hpp"
#include "hil_fixture.hpp"

namespace fullarm::hil {
namespace {

// Points of a link's surface, link frame: a mesh link's vertices; for a capsule link the two
// segment ends pushed out by the radius along 26 directions (the cube's faces, edges and
// corners), where a rigid motion moves the capsule's points farthest.
std::vector<Eigen::Vector3d> linkSurfaceSamples(const haptics::CollisionWorld& world, int link) {
  std::vector<Eigen::Vector3d> points;
  if (world.linkShape(link) == haptics::LinkShape::kMesh) {
    const haptics::TriMesh& mesh = world.linkMesh(link);
    for (int v = 0; v < mesh.numVertices(); ++v) points.push_back(mesh.vertex(v));
    return points;
  }
  const haptics::Capsule& capsule = world.linkCapsule(link);
  for (int x = -1; x <= 1; ++x) {
    for (int y = -1; y <= 1; ++y) {
      for (int z = -1; z <= 1; ++z) {
        if (x == 0 && y == 0 && z == 0) continue;
        const Eigen::Vector3d u = Eigen::Vector3d(x, y, z).normalized() * capsule.radius_m;
        points.push_back(capsule.a_m + u);
        points.push_back(capsule.b_m + u);
      }
    }
  }
  return points;
}

constexpr double kPeriod_s = 1e-3;

struct ValveScene {
  ValveScene()
      : scene(haptics::loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"))),
        world(haptics::makeCollisionWorld(scene, test::model())),
        params(haptics::loadHapticsParams(arm::test::sourcePath("config/haptics.yaml"))),
        gains(controllers::loadGainsConfig(arm::test::sourcePath("config/dts_gains.yaml"), test::model())),
        q_reach(haptics::scenePosture(scene, "reach_valve", test::model())) {}
  TickModel tickModel(haptics::RenderMode mode, double startup_s = 0.005) const {
    haptics::HapticsParams p = params;
    p.mode = mode;
    SupervisorParams s;
    s.startup_valid_s = startup_s;
    s.global_period_s = 0.01;
    return makeTickModel(test::model(), world, p, gains, s, test::armJoints(), q_reach);
  }
  haptics::Scene scene;
  haptics::CollisionWorld world;
  haptics::HapticsParams params;
  controllers::GainsConfig gains;
  Eigen::VectorXd q_reach;
};

const ValveScene& valveScene() {
  static const ValveScene s;
  return s;
}

std::vector<haptics::LocalMinimum> searchAt(const Eigen::VectorXd& q) {
  GlobalSearchRunner runner(test::model(), valveScene().world, valveScene().params);
  std::vector<haptics::LocalMinimum> out;
  runner.run(q, out);
  return out;
}

// A reading at configuration q (its arm joints) with the load cells of a user at rest holding
// the given contact torque: g(q) - tau_contact.
JointSample readingAt(const Eigen::VectorXd& q, const Eigen::VectorXd& tau_contact) {
  arm::ArmData fk(test::model());
  arm::computeGravityTorques(test::model(), fk, q);
  JointSample s;
  s.q_rad = q.head(7);
  s.tau_load_cell_nm = (fk.tau_gravity - tau_contact).head(7);
  return s;
}

Eigen::VectorXd slowMotion(int tick) {
  Eigen::VectorXd q = valveScene().q_reach;
  q[3] += 2e-4 * tick;
  q[0] -= 1e-4 * tick;
  return q;
}

TEST(Tick, ComposesThePiecesInOrderLikeTheHandComposedPath) {
  const ValveScene& vs = valveScene();
  const TickModel tick = vs.tickModel(haptics::RenderMode::kFullArm);
  TickData data(tick);
  const std::vector<haptics::LocalMinimum> found = searchAt(vs.q_reach);
  ASSERT_FALSE(found.empty());
  const std::vector<double> q_query(vs.q_reach.data(), vs.q_reach.data() + vs.q_reach.size());
  const MinimaDelivery delivery{7, found, q_query};

  // The hand-composed path (tests/haptics/tick_composition_test.cpp), run beside the tick.
  const arm::ArmModel& model = test::model();
  arm::ArmData fk(model);
  haptics::ContactData contact(model, kMaxTrackedMinima);
  controllers::ArmControllerData control;
  std::vector<haptics::LocalMinimum> minima = found;
  bool controller_started = false;
  Eigen::VectorXd tau_contact_previous = Eigen::VectorXd::Zero(model.numJoints());

  int running_ticks = 0;
  for (int k = 1; k <= 40; ++k) {
    const Eigen::VectorXd q = slowMotion(k);
    const JointSample sample = readingAt(q, tau_contact_previous);
    TickInputs in;
    in.sample = &sample;
    in.minima = k == 1 ? &delivery : nullptr;
    IoVector valve;
    TickTelemetry telemetry;
    const std::uint64_t fk_before = data.fk.forward_kinematics_passes;
    const std::uint64_t gravity_before = data.fk.gravity_passes;
    stepTick(tick, data, in, valve, telemetry);
    EXPECT_EQ(data.fk.forward_kinematics_passes - fk_before, 1u) << "tick " << k;
    EXPECT_EQ(data.fk.gravity_passes - gravity_before, 1u) << "tick " << k;

    arm::computeForwardKinematics(model, fk, q);
    const int kept = haptics::updateMinimaLocalDescent(vs.world, fk, minima, vs.params.descent);
    minima.resize(static_cast<std::size_t>(kept));
    haptics::computeContactForces(tick.haptics, model, fk, minima, kPeriod_s, contact);
    haptics::computeContactTorques(model, fk, minima, contact);
    arm::computeGravityTorquesAtKinematics(model, fk);
    Eigen::VectorXd expected_valve = Eigen::VectorXd::Zero(7);
    if (telemetry.forces_allowed) {
      ++running_ticks;
      if (!controller_started) {
        controllers::resetArmController(tick.controller, control, q);
        controller_started = true;
      }
      Eigen::VectorXd cells = sample.tau_load_cell_nm;
      Eigen::VectorXd out(7);
      controllers::stepArmController(tick.controller, control, q, fk.tau_gravity, contact.tau_contact_nm, cells, out);
      expected_valve = out;
    }
    ASSERT_EQ(telemetry.tracked_minima, kept) << "tick " << k;
    for (int j = 0; j < 7; ++j) {
      EXPECT_EQ(valve[j], expected_valve[j]) << "tick " << k << " joint " << j;
    }
    for (int j = 0; j < model.numJoints(); ++j) {
      EXPECT_EQ(telemetry.tau_contact_nm[static_cast<std::size_t>(j)], contact.tau_contact_nm[j]) << k;
      EXPECT_EQ(telemetry.tau_gravity_nm[static_cast<std::size_t>(j)], fk.tau_gravity[j]) << k;
    }
    tau_contact_previous = contact.tau_contact_nm;
  }
  EXPECT_GT(running_ticks, 20);
  EXPECT_GT(data.contact.active_springs, 0) << "the arm touches the wall at this posture";
}

TEST(Tick, DoesNotAllocateAdoptingASetIncluded) {
  const ValveScene& vs = valveScene();
  const TickModel tick = vs.tickModel(haptics::RenderMode::kFullArm);
  TickData data(tick);
  const std::vector<haptics::LocalMinimum> found = searchAt(vs.q_reach);
  const std::vector<double> q_query(vs.q_reach.data(), vs.q_reach.data() + vs.q_reach.size());
  const MinimaDelivery delivery{1, found, q_query};
  IoVector valve;
  TickTelemetry telemetry;
  for (int k = 1; k <= 60; ++k) {
    const JointSample sample = readingAt(slowMotion(k), Eigen::VectorXd::Zero(test::model().numJoints()));
    TickInputs in;
    in.sample = &sample;
    in.minima = k % 10 == 1 ? &delivery : nullptr;
    EXPECT_NO_HEAP_ALLOCATION(stepTick(tick, data, in, valve, telemetry));
  }
  EXPECT_TRUE(telemetry.forces_allowed);
}

TEST(Tick, HandOnlyRendersOnlyTheHandAndRecordsEveryLinksContact) {
  const ValveScene& vs = valveScene();
  const TickModel full = vs.tickModel(haptics::RenderMode::kFullArm);
  const TickModel hand = vs.tickModel(haptics::RenderMode::kHandOnly);
  TickData full_data(full);
  TickData hand_data(hand);
  const std::vector<haptics::LocalMinimum> found = searchAt(vs.q_reach);
  const std::vector<double> q_query(vs.q_reach.data(), vs.q_reach.data() + vs.q_reach.size());
  const MinimaDelivery delivery{1, found, q_query};
  TickTelemetry tf;
  TickTelemetry th;
  for (int k = 1; k <= 3; ++k) {
    const JointSample sample = readingAt(vs.q_reach, Eigen::VectorXd::Zero(test::model().numJoints()));
    TickInputs in;
    in.sample = &sample;
    in.minima = k == 1 ? &delivery : nullptr;
    IoVector valve;
    stepTick(full, full_data, in, valve, tf);
    stepTick(hand, hand_data, in, valve, th);
  }
  // The same contacts are recorded in both modes; hand-only renders only the hand's.
  EXPECT_EQ(tf.link_contact_mask, th.link_contact_mask);
  ASSERT_NE(tf.link_contact_mask, 0u);
  int non_hand_in_contact = 0;
  for (int l = 0; l < test::model().numJoints(); ++l) {
    if (((tf.link_contact_mask >> l) & 1u) && !haptics::isHandLink(test::model(), l)) ++non_hand_in_contact;
  }
  ASSERT_GT(non_hand_in_contact, 0) << "the reach posture has the forearm near the opening";
  EXPECT_LT(th.active_springs, tf.active_springs);
  for (std::size_t m = 0; m < static_cast<std::size_t>(hand_data.num_tracked); ++m) {
    if (hand_data.contact.rendered[m] != 0) {
      EXPECT_TRUE(haptics::isHandLink(test::model(), hand_data.tracked[m].link));
    }
  }
  for (int l = 0; l < test::model().numJoints(); ++l) {
    EXPECT_EQ(tf.link_depth_m[static_cast<std::size_t>(l)], th.link_depth_m[static_cast<std::size_t>(l)]) << l;
  }
}

TEST(Tick, SweepBoundsEveryLinkPointAndFlagsBeyondTheLookAhead) {
  const ValveScene& vs = valveScene();
  const TickModel tick = vs.tickModel(haptics::RenderMode::kFullArm);
  TickData data(tick);
  const Eigen::VectorXd q0 = vs.q_reach;
  const std::vector<double> q_query(q0.data(), q0.data() + q0.size());
  const MinimaDelivery delivery{1, {}, q_query};
  arm::ArmData fk0(test::model());
  arm::computeForwardKinematics(test::model(), fk0, q0);
  arm::ArmData fk(test::model());
  for (int k = 1; k <= 200; ++k) {
    Eigen::VectorXd q = q0;
    q[0] -= 1e-3 * k;  // 0.2 rad of shoulder motion
    q[3] += 5e-4 * k;
    const JointSample sample = readingAt(q, Eigen::VectorXd::Zero(test::model().numJoints()));
    TickInputs in;
    in.sample = &sample;
    in.minima = k == 1 ? &delivery : nullptr;
    IoVector valve;
    TickTelemetry t;
    stepTick(tick, data, in, valve, t);
    arm::computeForwardKinematics(test::model(), fk, q);
    for (int l = 0; l < test::model().numJoints(); ++l) {
      if (!vs.world.hasLinkGeometry(l)) continue;
      const std::vector<Eigen::Vector3d> points = linkSurfaceSamples(vs.world, l);
      double worst = 0.0;
      for (const Eigen::Vector3d& p : points) {
        const Eigen::Vector3d a = fk.X_WL[static_cast<std::size_t>(l)] * p;
        const Eigen::Vector3d b = fk0.X_WL[static_cast<std::size_t>(l)] * p;
        worst = std::max(worst, (a - b).norm());
      }
      const double bound = t.link_sweep_m[static_cast<std::size_t>(l)];
      EXPECT_GE(bound, worst - 1e-12) << "link " << l << " tick " << k;
      EXPECT_EQ(((t.sweep_exceeded_mask >> l) & 1u) != 0, bound > tick.sweep_limit_m);
    }
    if (k == 200) {
      EXPECT_NE(t.sweep_exceeded_mask, 0u) << "0.2 rad at the shoulder sweeps the hand beyond L - d_f";
    }
    if (k == 2) {
      EXPECT_EQ(t.sweep_exceeded_mask, 0u);
    }
  }
}

TEST(Tick, StaleMinimaFadeTheContactTorques) {
  const ValveScene& vs = valveScene();
  const TickModel tick = vs.tickModel(haptics::RenderMode::kFullArm);
  TickData data(tick);
  const std::vector<haptics::LocalMinimum> found = searchAt(vs.q_reach);
  const std::vector<double> q_query(vs.q_reach.data(), vs.q_reach.data() + vs.q_reach.size());
  const MinimaDelivery delivery{1, found, q_query};
  const JointSample sample = readingAt(vs.q_reach, Eigen::VectorXd::Zero(test::model().numJoints()));
  TickTelemetry t;
  bool stale_event = false;
  double first_norm = 0.0;
  for (int k = 1; k <= 400; ++k) {
    TickInputs in;
    in.sample = &sample;
    in.minima = (k <= 20 && k % 10 == 1) ? &delivery : nullptr;  // then the search stalls
    IoVector valve;
    stepTick(tick, data, in, valve, t);
    const double norm = Eigen::Map<const Eigen::VectorXd>(t.tau_contact_nm.data(), t.num_config).norm();
    if (k == 15) first_norm = norm;
    for (int e = 0; e < t.num_events; ++e) {
      stale_event = stale_event || t.events[static_cast<std::size_t>(e)].cause == SupervisorCause::kMinimaStale;
    }
  }
  EXPECT_GT(first_norm, 0.0);
  EXPECT_TRUE(stale_event);
  EXPECT_EQ(t.contact_scale, 0.0);
  EXPECT_EQ(Eigen::Map<const Eigen::VectorXd>(t.tau_contact_nm.data(), t.num_config).norm(), 0.0);
  EXPECT_GT(t.tracked_minima, 0) << "the tick keeps descending its old minima";
}

}  // namespace
}  // namespace fullarm::hil
