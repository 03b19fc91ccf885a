// Static holds on the simulated DTS whose arm is a perturbed default (the truth the test knows):
// the base parameters fitted from its holds predict the plant's own gravity torques at held-out
// postures. The holds log round-trips through its CSV.

#include <gtest/gtest.h>

#include <cstdio>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/core/random.hpp"
#include "fullarm/hil/sim_io.hpp"
#include "fullarm/identification/gravity.hpp"
#include "fullarm/identification/static_holds.hpp"
#include "hil_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::identification {
namespace {

Eigen::VectorXd gravity(const arm::ArmModel& model, const Eigen::VectorXd& q) {
  arm::ArmData data(model);
  arm::computeGravityTorques(model, data, q);
  return data.tau_gravity;
}

/// The default arm with its masses and centres of mass moved (inside the link geometry).
arm::ArmModel perturbedTruth() {
  arm::ArmModel truth = hil::test::model();
  for (std::size_t i = 0; i < truth.joints.size(); ++i) {
    auto& link = truth.joints[i].inertial;
    if (link.mass_kg <= 0.0) continue;
    link.mass_kg *= (i % 2 == 0) ? 0.8 : 1.1;
    link.com_m += Eigen::Vector3d(0.01, -0.005, 0.01);
  }
  return truth;
}

/// `count` device-order postures inside the limits less `inset`.
std::vector<Eigen::VectorXd> devicePostures(const arm::JointSelection& joints, int count, double inset,
                                            std::uint64_t stream) {
  const arm::ArmModel& model = hil::test::model();
  std::vector<Eigen::VectorXd> out;
  for (int p = 0; p < count; ++p) {
    core::RandomStream rng(23, stream, static_cast<std::uint64_t>(p));
    Eigen::VectorXd q(joints.size());
    for (int k = 0; k < joints.size(); ++k) {
      const auto& limits = model.joints[static_cast<std::size_t>(joints.modelIndex(k))].limits;
      q[k] = rng.uniform(limits.min_rad + inset, limits.max_rad - inset);
    }
    out.push_back(q);
  }
  return out;
}

// The device joints' limits, from the model.
void setLimits(StaticHoldOptions& options, const arm::ArmModel& model, const arm::JointSelection& joints) {
  for (int k = 0; k < joints.size(); ++k) {
    const auto& limits = model.joints[static_cast<std::size_t>(joints.modelIndex(k))].limits;
    options.min_rad.push_back(limits.min_rad);
    options.max_rad.push_back(limits.max_rad);
  }
}

TEST(StaticHoldsSimTest, FittedBaseParametersPredictThePlantsGravityAtHeldOutPostures) {
  const arm::ArmModel& nominal = hil::test::model();
  const arm::ArmModel truth = perturbedTruth();
  plant::PlantConfig plant_config = plant::loadPlantConfig(arm::test::sourcePath("config/dts_plant.yaml"), truth);
  plant_config.solver.integrator = plant::IntegratorKind::kRodas3;
  hil::SimulatedArm arm(truth, plant_config, hil::test::restPosture(), 1e-3, 1);
  hil::SimIoDevice device(arm, {}, hil::IoSafetyParams{0.2, 10.0});
  const arm::JointSelection& joints = arm.joints();

  StaticHoldOptions options;
  options.move_s = 1.5;
  options.approach_s = 0.5;
  options.settle_s = 1.0;
  options.average_s = 0.3;
  setLimits(options, nominal, joints);
  const auto postures = devicePostures(joints, 16, 0.15, 1);
  // A posture whose approach leaves the limits is refused before the arm moves.
  Eigen::VectorXd too_close = postures.front();
  too_close[3] = options.max_rad[3] - 0.03;  // elbow: 0.03 + 0.05 approach > 0.02 margin
  EXPECT_THROW((void)runStaticHolds(device, {too_close}, options), std::invalid_argument);
  EXPECT_EQ(device.state(), hil::IoState::kInactive);
  const StaticHoldRun run = runStaticHolds(device, postures, options);
  ASSERT_TRUE(run.completed) << run.stop_reason;
  ASSERT_EQ(run.holds.size(), 2 * postures.size());
  EXPECT_EQ(device.state(), hil::IoState::kInactive);

  // The log round-trips (17 significant digits).
  std::vector<std::string> names;
  for (int k = 0; k < joints.size(); ++k)
    names.push_back(nominal.joints[static_cast<std::size_t>(joints.modelIndex(k))].name);
  const auto dir = fullarm::test::scratchDir("static_holds_sim");
  writeStaticHoldsCsv(dir / "holds.csv", run.holds, names);
  const auto read_back = readStaticHoldsCsv(dir / "holds.csv", names);
  ASSERT_EQ(read_back.size(), run.holds.size());
  for (std::size_t h = 0; h < read_back.size(); ++h) {
    EXPECT_EQ(read_back[h].side, run.holds[h].side);
    EXPECT_EQ((read_back[h].tau_nm - run.holds[h].tau_nm).cwiseAbs().maxCoeff(), 0.0);
  }

  std::vector<Eigen::VectorXd> q_fit;
  std::vector<Eigen::VectorXd> tau_fit;
  double worst_q_error = 0.0;
  for (const auto& c : combineSides(read_back)) {
    q_fit.push_back(holdConfiguration(hil::test::restPosture(), joints, c.q_rad));
    Eigen::VectorXd tau = Eigen::VectorXd::Zero(nominal.numJoints());
    joints.scatter(c.tau_nm, tau);
    tau_fit.push_back(tau);
    worst_q_error =
        std::max(worst_q_error, (c.q_rad - postures[static_cast<std::size_t>(c.posture_index)]).cwiseAbs().maxCoeff());
  }
  std::printf("largest hold error from the commanded posture %.4f rad\n", worst_q_error);
  std::vector<int> measured;
  for (int k = 0; k < joints.size(); ++k) measured.push_back(joints.modelIndex(k));
  const GravityFit fit = fitGravityParameters(nominal, q_fit, tau_fit, measured);
  ASSERT_TRUE(fit.positive_masses);
  const arm::ArmModel fitted = withGravityParameters(nominal, fit.parameters);
  std::printf("residual per joint [N m]:");
  for (int k = 0; k < joints.size(); ++k) std::printf(" %.4f", fit.residual_rms_nm[joints.modelIndex(k)]);
  std::printf("\n");

  // Tolerance: half a step of the elbow and wrist-rotation load cells (12 bits, 0.0249 N m a
  // step), the largest quantisation error of one reading; the holds average many readings over
  // many postures, so the fitted gravity is held to that on every joint.
  const double tolerance_nm = 0.5 * 0.02488643;
  double worst = 0.0;
  for (const auto& q_device : devicePostures(joints, 20, 0.1, 2)) {
    const Eigen::VectorXd q = holdConfiguration(hil::test::restPosture(), joints, q_device);
    const Eigen::VectorXd error = gravity(fitted, q) - gravity(truth, q);
    for (int k = 0; k < joints.size(); ++k) worst = std::max(worst, std::abs(error[joints.modelIndex(k)]));
  }
  std::printf("largest held-out gravity error %.4f N m\n", worst);
  EXPECT_LT(worst, tolerance_nm);
  // The nominal model is measurably off (the test would pass without a fit otherwise).
  double nominal_worst = 0.0;
  for (const auto& q_device : devicePostures(joints, 20, 0.1, 2)) {
    const Eigen::VectorXd q = holdConfiguration(hil::test::restPosture(), joints, q_device);
    nominal_worst = std::max(nominal_worst, (gravity(nominal, q) - gravity(truth, q)).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(nominal_worst, 10.0 * tolerance_nm);
}

// An arm resting with its elbow at the lower stop, inside the run's margin (as the hydraulic
// arm hangs when it is off): the first move takes it out, no closer to the stop than it started,
// and every hold is taken.
TEST(StaticHoldsSimTest, AnArmRestingInsideTheMarginMovesOutOnTheFirstMove) {
  const arm::ArmModel& model = hil::test::model();
  plant::PlantConfig plant_config = plant::loadPlantConfig(arm::test::sourcePath("config/dts_plant.yaml"), model);
  plant_config.solver.integrator = plant::IntegratorKind::kRodas3;
  const int elbow = model.jointIndex("R_EB");
  ASSERT_GE(elbow, 0);
  Eigen::VectorXd rest = hil::test::restPosture();
  rest[elbow] = model.joints[static_cast<std::size_t>(elbow)].limits.min_rad + 0.008;
  hil::SimulatedArm arm(model, plant_config, rest, 1e-3, 1);
  hil::SimIoDevice device(arm, {}, hil::IoSafetyParams{0.2, 10.0});
  const arm::JointSelection& joints = arm.joints();

  StaticHoldOptions options;
  options.approach_s = 0.3;
  options.settle_s = 0.3;
  options.average_s = 0.1;
  setLimits(options, model, joints);
  int device_elbow = -1;
  for (int k = 0; k < joints.size(); ++k) {
    if (joints.modelIndex(k) == elbow) device_elbow = k;
  }
  ASSERT_GE(device_elbow, 0);
  const auto de = static_cast<std::size_t>(device_elbow);
  ASSERT_LT(rest[elbow], options.min_rad[de] + options.limit_margin_rad);  // inside the margin

  const auto postures = devicePostures(joints, 1, 0.15, 3);
  const StaticHoldRun run = runStaticHolds(device, postures, options);
  ASSERT_TRUE(run.completed) << run.stop_reason;
  ASSERT_EQ(run.holds.size(), 2u);
  for (const StaticHold& h : run.holds) {
    EXPECT_NEAR(h.q_rad[device_elbow], postures.front()[device_elbow], 0.03);
  }
}

}  // namespace
}  // namespace fullarm::identification
