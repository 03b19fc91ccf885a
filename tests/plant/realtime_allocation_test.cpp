// step() must not touch the heap: single joint and whole arm, across command jumps
// (re-initialisation), hard-stop events (root finding) and both input modes.

#include <gtest/gtest.h>

#include <vector>

#include "alloc_guard.hpp"
#include "plant_fixture.hpp"
#include "plant_test_util.hpp"

namespace fullarm::plant {
namespace {

TEST(PlantRealtime, GuardIsActive) {
  EXPECT_TRUE(fullarm::testing::allocatorInterposed());
}

class PlantRealtimeIntegrators : public ::testing::TestWithParam<IntegratorKind> {};

TEST_P(PlantRealtimeIntegrators, SingleJointStepDoesNotAllocate) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  for (const InputMode mode : {InputMode::kValveVoltage, InputMode::kTorqueLoop}) {
    JointParams p = config.joints[static_cast<std::size_t>(findPlantJoint(config, "EB"))];
    p.input_mode = mode;
    ArmPlant plant;
    SolverOptions options = config.solver;
    options.integrator = GetParam();
    plant.configure(model, {p}, model.defaultPosture(), config.user_arm, options, config.seed);
    PlantCommand cmd = PlantCommand::zero(1);
    for (int k = 0; k < 1200; ++k) {
      // Full-scale square wave: jumps (re-init) and slams into both stops (root events).
      cmd.command[0] = (k / 300) % 2 == 0 ? 10.0 : -10.0;
      if (mode == InputMode::kTorqueLoop) cmd.command[0] *= 5.0;
      core::RtStatus status;
      EXPECT_NO_HEAP_ALLOCATION(status = plant.step(1e-3, cmd));
      ASSERT_TRUE(status.ok()) << plant.lastError();
    }
    EXPECT_GT(plant.stats().root_events, 0) << "the test must exercise hard-stop events";
    if (GetParam() == IntegratorKind::kCvodes) {
      EXPECT_GT(plant.stats().reinits, 2);
    }
  }
}

TEST_P(PlantRealtimeIntegrators, WholeArmStepDoesNotAllocate) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  UserArmParams user = config.user_arm;
  user.enabled = true;
  ArmPlant plant;
  SolverOptions options = config.solver;
  options.integrator = GetParam();
  plant.configure(model, config.joints, model.defaultPosture(), user, options, config.seed);
  PlantCommand cmd = PlantCommand::zero(plant.numJoints());
  for (int k = 0; k < 60; ++k) {
    for (int j = 0; j < plant.numJoints(); ++j) cmd.command[j] = (k / 20) % 2 == 0 ? 4.0 : -4.0;
    cmd.tau_user_nm[0] = 1.0;
    cmd.tau_contact_nm[3] = -2.0;
    core::RtStatus status;
    EXPECT_NO_HEAP_ALLOCATION(status = plant.step(1e-3, cmd));
    ASSERT_TRUE(status.ok()) << plant.lastError();
  }
  if (GetParam() == IntegratorKind::kCvodes) {
    EXPECT_GT(plant.stats().reinits, 1);
  }
}

// Rodas3 with the dense Newton matrix (torque-loop joints on the whole arm couple every joint's
// valve to every pressure through M^-1, so the block elimination is off).
TEST(PlantRealtime, WholeArmTorqueLoopRodas3StepDoesNotAllocate) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  std::vector<JointParams> joints = config.joints;
  for (JointParams& p : joints) p.input_mode = InputMode::kTorqueLoop;
  SolverOptions options = config.solver;
  options.integrator = IntegratorKind::kRodas3;
  ArmPlant plant;
  plant.configure(model, joints, model.defaultPosture(), config.user_arm, options, config.seed);
  PlantCommand cmd = PlantCommand::zero(plant.numJoints());
  for (int k = 0; k < 60; ++k) {
    for (int j = 0; j < plant.numJoints(); ++j) cmd.command[j] = (k / 20) % 2 == 0 ? 5.0 : -5.0;
    core::RtStatus status;
    EXPECT_NO_HEAP_ALLOCATION(status = plant.step(1e-3, cmd));
    ASSERT_TRUE(status.ok()) << plant.lastError();
  }
  EXPECT_GT(plant.stats().steps, 60);
}

// The opt-in reuse of the rigid-body derivatives within a period (SolverOptions).
TEST(PlantRealtime, WholeArmRodas3RigidDerivativesOncePerPeriodStepDoesNotAllocate) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  SolverOptions options = config.solver;
  options.integrator = IntegratorKind::kRodas3;
  options.rigid_derivatives_once_per_period = true;
  ArmPlant plant;
  plant.configure(model, config.joints, model.defaultPosture(), config.user_arm, options, config.seed);
  PlantCommand cmd = PlantCommand::zero(plant.numJoints());
  for (int k = 0; k < 60; ++k) {
    for (int j = 0; j < plant.numJoints(); ++j) cmd.command[j] = (k / 20) % 2 == 0 ? 4.0 : -4.0;
    core::RtStatus status;
    EXPECT_NO_HEAP_ALLOCATION(status = plant.step(1e-3, cmd));
    ASSERT_TRUE(status.ok()) << plant.lastError();
  }
  EXPECT_GT(plant.stats().steps, 60);
}

INSTANTIATE_TEST_SUITE_P(Integrators, PlantRealtimeIntegrators,
                         ::testing::Values(IntegratorKind::kCvodes, IntegratorKind::kRodas3, IntegratorKind::kRodas4,
                                           IntegratorKind::kRos34pw2),
                         [](const ::testing::TestParamInfo<IntegratorKind>& param_info) {
                           return param_info.param == IntegratorKind::kCvodes   ? "Cvodes"
                                  : param_info.param == IntegratorKind::kRodas3 ? "Rodas3"
                                  : param_info.param == IntegratorKind::kRodas4 ? "Rodas4"
                                                                                : "Ros34pw2";
                         });

}  // namespace
}  // namespace fullarm::plant
