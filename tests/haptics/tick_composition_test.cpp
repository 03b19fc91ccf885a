// The 1 kHz tick's pieces composed in order on the valve scene (docs/architecture.md): forward
// kinematics, local descent of the minima a global search handed over, contact springs,
// tailored Jacobian torques (Eq. 1-2), gravity, the arm controller. The kinematics and the
// gravity torques are computed exactly once per tick: every piece after the first reads them.

#include <gtest/gtest.h>

#include <vector>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/controllers/arm_controller.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/local_descent.hpp"
#include "fullarm/haptics/scene.hpp"

namespace fullarm::haptics {
namespace {

constexpr double kTick_s = 1e-3;

TEST(TickComposition, OneKinematicsPassAndOneGravityPassPerTick) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  const CollisionWorld world = makeCollisionWorld(scene, model);
  const HapticsParams params = loadHapticsParams(arm::test::sourcePath("config/haptics.yaml"));
  const controllers::GainsConfig gains =
      controllers::loadGainsConfig(arm::test::sourcePath("config/dts_gains.yaml"), model);
  const controllers::ArmControllerModel controller = controllers::makeArmControllerModel(gains, model);
  const int n = controller.numJoints();

  // Off the tick (the global-search thread): the minima at the reach posture.
  const Eigen::VectorXd q0 = scenePosture(scene, "reach_valve", model);
  arm::ArmData search_fk(model);
  arm::computeForwardKinematics(model, search_fk, q0);
  std::vector<LocalMinimum> minima;
  SnchGlobalSearch search;
  search.search(world, search_fk, params.cutoff_m, params.prune_radius_m, minima);
  ASSERT_FALSE(minima.empty());

  // Scratch of the tick, preallocated.
  arm::ArmData fk(model);
  ContactData contact(model, static_cast<int>(minima.size()));
  controllers::ArmControllerData control;
  controllers::resetArmController(controller, control, q0);
  Eigen::VectorXd cells(n);
  Eigen::VectorXd valve_v(n);

  // A few ticks of a slow motion away from the reach posture.
  for (int tick = 1; tick <= 5; ++tick) {
    Eigen::VectorXd q = q0;
    q[3] += 2e-4 * tick;
    const std::uint64_t fk_before = fk.forward_kinematics_passes;
    const std::uint64_t gravity_before = fk.gravity_passes;

    arm::computeForwardKinematics(model, fk, q);
    const int kept = updateMinimaLocalDescent(world, fk, minima, params.descent);
    const std::span<const LocalMinimum> live(minima.data(), static_cast<std::size_t>(kept));
    computeContactForces(params, model, fk, live, kTick_s, contact);
    computeContactTorques(model, fk, live, contact);
    arm::computeGravityTorquesAtKinematics(model, fk);
    // The load cells of a user at rest read g(q) minus the contact torque the arm holds.
    controller.selection.gather(fk.tau_gravity - contact.tau_contact_nm, cells);
    controllers::stepArmController(controller, control, q, fk.tau_gravity, contact.tau_contact_nm, cells, valve_v);

    EXPECT_EQ(fk.forward_kinematics_passes - fk_before, 1u) << "tick " << tick;
    EXPECT_EQ(fk.gravity_passes - gravity_before, 1u) << "tick " << tick;
    ASSERT_GT(kept, 0);
    EXPECT_TRUE(contact.status.ok()) << contact.status.message;
    EXPECT_TRUE(control.status.ok()) << control.status.message;
    // The pieces saw this tick's configuration: gravity equals a fresh computation at q.
    arm::ArmData reference(model);
    arm::computeGravityTorques(model, reference, q);
    EXPECT_EQ(fk.tau_gravity, reference.tau_gravity) << "tick " << tick;
    EXPECT_TRUE(valve_v.allFinite());
  }
  EXPECT_GT(contact.active_springs, 0);  // the arm touches the wall at this posture
  EXPECT_GT(contact.tau_contact_nm.norm(), 0.0);
}

}  // namespace
}  // namespace fullarm::haptics
