// The arm-level tuning pipeline (design::tuneArm): the linear stage of each joint is tuneJoint on
// the documented joint model and goals (recomputed here by direct calls), the written file holds
// the stages' gains and the start elsewhere, a joint's result depends neither on the other joints
// nor on the thread count, the default budget reproduces the shipped gains file (an earlier run's
// output), and bad input names its key.

#include <gtest/gtest.h>

#include <stdexcept>
#include <string>

#include "design_fixture.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/design/tune_arm.hpp"

namespace fullarm::design {
namespace {

const controllers::GainsConfig& startGains() {
  static const controllers::GainsConfig g =
      controllers::loadGainsConfig(controllers::defaultTuneStartGainsPath(), test::dtsModel());
  return g;
}

const ValidationConfig& validation() {
  static const ValidationConfig c = loadValidationConfig(defaultValidationConfigPath());
  return c;
}

const controllers::JointGains& jointOf(const controllers::GainsConfig& g, const std::string& name) {
  return g.joints[static_cast<std::size_t>(controllers::findGainsJoint(g, name))];
}

void expectSameGains(const controllers::JointGains& a, const controllers::JointGains& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.impedance.inertia_kgm2, b.impedance.inertia_kgm2) << a.name;
  EXPECT_EQ(a.impedance.damping_nms_per_rad, b.impedance.damping_nms_per_rad) << a.name;
  EXPECT_EQ(a.impedance.stiffness_nm_per_rad, b.impedance.stiffness_nm_per_rad) << a.name;
  EXPECT_EQ(a.sliding_mode.lambda_per_s, b.sliding_mode.lambda_per_s) << a.name;
  EXPECT_EQ(a.sliding_mode.valve_bound_v, b.sliding_mode.valve_bound_v) << a.name;
  EXPECT_EQ(a.sliding_mode.boundary_layer_radps, b.sliding_mode.boundary_layer_radps) << a.name;
}

// A small budget: enough to move the gains, cheap enough for a test.
ArmTuningOptions smallBudget(std::vector<std::string> joints, int nonlinear_rounds, int threads) {
  ArmTuningOptions o;
  o.joints = std::move(joints);
  o.global_evaluations = 40;
  o.local_evaluations = 20;
  o.rounds = 2;
  o.nonlinear_rounds = nonlinear_rounds;
  o.threads = threads;
  return o;
}

TEST(TuneArm, LinearStageIsTuneJointOnTheTunersJointModelAndValidatesGoals) {
  const arm::ArmModel& model = test::dtsModel();
  const ArmTuningResult run =
      tuneArm(model, test::dtsPlant(), startGains(), validation(), smallBudget({"EB", "WR"}, 0, 2));
  ASSERT_EQ(run.results.size(), 2u);
  EXPECT_TRUE(run.stages.empty());
  bool all_feasible = true;
  for (const std::string name : {"R_EB", "R_WR"}) {
    const std::size_t k = name == "R_EB" ? 0 : 1;
    ASSERT_EQ(run.results[k].joint, name);
    // The same stage by direct calls: the joint model, posture, setup, goals and seed that
    // tune_arm.hpp documents.
    const controllers::JointGains& initial = jointOf(startGains(), name);
    const JointPlantModel jm = tunerJointModel(model, test::dtsPlant(), validation(), name);
    const double q = model.defaultPosture()[model.jointIndex(name)];
    LoopSetup setup;
    setup.control_period_s = startGains().control_period_s;
    setup.delay_samples = validation().ranges.delay_min_samples;
    const JointScenario sc =
        validationScenario(makeJointScenario(model, test::dtsPlant(), startGains(), name), validation());
    TuningGoals goals;
    goals.wall_stiffness_nm_per_rad = validation().wall.stiffness_nm_per_rad;
    goals.wall_damping_nms_per_rad = validation().wall.damping_nms_per_rad;
    goals.detector = detectorModelOf(sc);
    goals.detector.modal_amplitude = true;
    goals.contact_detector = contactDetectorModelOf(sc);
    TunerOptions options;
    options.global_evaluations = 40;
    options.local_evaluations = 20;
    options.rounds = 2;
    const TuningResult direct = tuneJoint(jm, q, initial, setup, goals, TuningBounds{}, validation().ranges, options);
    expectSameGains(run.results[k].tuned, direct.tuned);
    EXPECT_EQ(run.results[k].evaluations, direct.evaluations);
    EXPECT_EQ(run.results[k].model_set.size(), direct.model_set.size());
    // Without the nonlinear stage the file holds the linear stage's gains.
    expectSameGains(jointOf(run.tuned, name), direct.tuned);
    all_feasible = all_feasible && direct.feasible;
    // The contact goal is reported (computed, not a default) although it is not a hard goal.
    EXPECT_GT(run.contact[k].spectral_radius, 0.5) << name;
  }
  EXPECT_EQ(run.pass, all_feasible);
  // Untuned joints are the start's; the written file has no source.
  for (const std::string name : {"R_SFE", "R_SAA", "R_HR", "R_WFE", "R_WAA"}) {
    expectSameGains(jointOf(run.tuned, name), jointOf(startGains(), name));
  }
  EXPECT_TRUE(run.tuned.source.empty());
}

TEST(TuneArm, AJointsResultDependsNeitherOnTheOtherJointsNorOnTheThreadCount) {
  const ArmTuningResult alone =
      tuneArm(test::dtsModel(), test::dtsPlant(), startGains(), validation(), smallBudget({"WR"}, 1, 1));
  const ArmTuningResult with_eb =
      tuneArm(test::dtsModel(), test::dtsPlant(), startGains(), validation(), smallBudget({"EB", "WR"}, 1, 2));
  ASSERT_EQ(alone.stages.size(), 1u);
  ASSERT_EQ(with_eb.stages.size(), 2u);
  expectSameGains(alone.results[0].tuned, with_eb.results[1].tuned);
  expectSameGains(alone.stages[0].gains, with_eb.stages[1].gains);
  EXPECT_EQ(alone.stages[0].simulations, with_eb.stages[1].simulations);
  EXPECT_EQ(alone.stages[0].check_failures, with_eb.stages[1].check_failures);
  EXPECT_EQ(alone.stages[0].verified, with_eb.stages[1].verified);
  // With the stage on, the file holds the stage's gains.
  expectSameGains(jointOf(with_eb.tuned, "WR"), with_eb.stages[1].gains);
  expectSameGains(jointOf(with_eb.tuned, "EB"), with_eb.stages[0].gains);
  EXPECT_EQ(with_eb.pass, with_eb.stages[0].verified && with_eb.stages[1].verified);
}

TEST(TuneArm, BadInputNamesItsKey) {
  controllers::GainsConfig pid = startGains();
  pid.controller = controllers::ControllerKind::kTorquePid;
  try {
    (void)tuneArm(test::dtsModel(), test::dtsPlant(), pid, validation(), smallBudget({"WR"}, 0, 1));
    ADD_FAILURE() << "a torque-PID gains file was tuned";
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "controller") << e.what();
    EXPECT_NE(e.message().find("torque_pid"), std::string::npos) << e.what();
  }
  try {
    (void)tuneArm(test::dtsModel(), test::dtsPlant(), startGains(), validation(), smallBudget({"XX"}, 0, 1));
    ADD_FAILURE() << "an unknown joint was tuned";
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("XX"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)tuneArm(test::dtsModel(), test::dtsPlant(), startGains(), validation(), smallBudget({"WR"}, 0, 0)),
               std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::design
