// The grey-box fit on data from the simulated DTS itself (the CVODES-class hydraulic plant of
// fullarm::plant with its 12-bit sensors and their noise, the elbow alone with its neighbours
// locked): from a corner of a x3 box the identified flow gain, hydraulic stiffness, leakage,
// inertia, static load and Coulomb friction lie within 10 % of the plant's own groups at the
// operating angle (greyModelFromJoint), the delay is the device's latency, and the model fits a
// held-out experiment at >= 90 % in angle and torque. From angle and load cell alone the viscous
// friction is not recovered; with the chamber pressures logged as well (transducers on the
// simulated elbow) it is, within 10 %, with every other group.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/hil/sim_io.hpp"
#include "fullarm/identification/excitation.hpp"
#include "fullarm/identification/experiment.hpp"
#include "fullarm/identification/grey_box.hpp"
#include "fullarm/identification/joint_groups.hpp"
#include "fullarm/identification/validation.hpp"
#include "hil_fixture.hpp"

namespace fullarm::identification {
namespace {

constexpr double kT = 1.0e-3;
constexpr int kLatency = 1;
constexpr int kElbow = 3;

// The elbow alone on the simulated DTS (the plant's single-joint mode), at the fixture's posture.
// With `pressure_transducers` the elbow's chambers get 0-25 MPa transducers (12 bits, 10 kPa of
// noise) and the log carries their readings, turned into the hydraulic torque.
ExperimentData runOnElbow(const SampledSignal& r, std::uint64_t seed, bool pressure_transducers = false) {
  plant::PlantConfig config = hil::test::plantConfig();
  plant::JointParams elbow = config.joints[kElbow];
  if (pressure_transducers) {
    elbow.sensor_noise.pressure_full_scale_pa = 25.0e6;
    elbow.sensor_noise.pressure_bits = 12;
    elbow.sensor_noise.pressure_noise_pa = 1.0e4;
  }
  config.joints = {elbow};
  config.seed = seed;
  hil::SimulatedArm arm(hil::test::model(), config, hil::test::restPosture(), kT, kLatency);
  hil::SimIoDevice device(arm, {}, hil::IoSafetyParams{});
  ExperimentOptions options;
  options.joint = 0;
  options.min_rad = elbow.min_rad;
  options.max_rad = elbow.max_rad;
  const ExperimentResult result = runExperiment(device, r, options);
  EXPECT_TRUE(result.completed) << result.stop_reason;
  EXPECT_EQ(result.log.has("pressure_a_pa"), pressure_transducers);
  ExperimentData data = experimentFromLog(result.log);
  addHydraulicTorque(data, result.log, elbow);
  return data;
}

// The plant's groups at the experiment's mean angle, with the locked arm's inertia and gravity.
GreyModel plantGroups(const ExperimentData& data) {
  const plant::JointParams& elbow = hil::test::plantConfig().joints[kElbow];
  double q_mean = 0.0;
  for (double q : data.q_rad) q_mean += q;
  q_mean /= static_cast<double>(data.q_rad.size());
  const arm::ArmModel& model = hil::test::model();
  Eigen::VectorXd q = hil::test::restPosture();
  q[kElbow] = q_mean;
  arm::ArmData fk(model);
  arm::computeMassMatrix(model, fk, q);
  arm::computeGravityTorques(model, fk, q);
  GreyModel m = greyModelFromJoint(elbow, q_mean, fk.mass_matrix(kElbow, kElbow), fk.tau_gravity[kElbow], kLatency);
  q[kElbow] = q_mean + 1e-4;
  arm::computeGravityTorques(model, fk, q);
  const double up = fk.tau_gravity[kElbow];
  q[kElbow] = q_mean - 1e-4;
  arm::computeGravityTorques(model, fk, q);
  m.load_gradient_nm_per_rad = (up - fk.tau_gravity[kElbow]) / 2e-4;
  return m;
}

// The fit of the tests below: from a corner of a x3 box about the plant's groups (the Stribeck
// friction held at its value), printed beside them.
FitResult fitFromACorner(const ExperimentData& fit_data, const GreyModel& truth) {
  GreyModel start = truth;
  start.delay_samples = 0;
  const std::array<double, 6> corner{2.5, 0.4, 2.5, 0.4, 2.5, 0.4};
  int c = 0;
  for (int i : {kFlowGain, kStiffness, kLeakage, kInertia, kViscous, kCoulomb}) {
    start.value[static_cast<std::size_t>(i)] *= corner[static_cast<std::size_t>(c++)];
  }
  FitOptions options = defaultFitOptions(truth, 3.0);
  options.params[kStribeck].free = false;
  options.global_samples = 30;
  options.polished_candidates = 1;
  options.max_iterations = 30;
  options.threads = 2;
  const FitResult fit = fitGreyModel({fit_data}, start, options);
  std::printf("cost %.4g, %d simulations, global %.1f s, polish %.1f s, delay %d\n", fit.cost, fit.evaluations,
              fit.global_seconds, fit.polish_seconds, fit.model.delay_samples);
  for (int i : {kFlowGain, kStiffness, kLeakage, kInertia, kViscous, kCoulomb, kLoadTorque}) {
    const auto k = static_cast<std::size_t>(i);
    std::printf("%-32s %.5g (plant %.5g) +- %.3g\n", greyParamName(i), fit.model.value[k], truth.value[k],
                fit.standard_error[k]);
  }
  return fit;
}

TEST(PlantFitTest, TheElbowsGroupsAreRecoveredFromTheSimulatedPlant) {
  const ExperimentData fit_data = runOnElbow(prbs(1.0, 8, prbsClockSamplesForBand(30.0, kT), 1, kT), 11);
  const ExperimentData held_out = runOnElbow(schroederMultisine(1.0, 0.25, 30.0, 4.0, 1, kT).signal, 12);
  const GreyModel truth = plantGroups(fit_data);

  const FitResult fit = fitFromACorner(fit_data, truth);
  EXPECT_EQ(fit.model.delay_samples, kLatency);
  for (int i : {kFlowGain, kStiffness, kLeakage, kInertia, kLoadTorque}) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_NEAR(fit.model.value[k], truth.value[k], 0.10 * truth.value[k]) << greyParamName(i);
  }
  // Coulomb friction is recovered to 10 %; the viscous group is not (here it goes to the box's
  // upper bound, three times the plant's, on fullarm identify's default run 40 % low: the structure
  // the reduced model still leaves out trades against it, docs/identification.md).
  EXPECT_NEAR(fit.model.value[kCoulomb], truth.value[kCoulomb], 0.10 * truth.value[kCoulomb]);

  ValidationThresholds thresholds;
  const ModelValidation v = validateModel(fit.model, held_out, thresholds);
  std::printf("held-out fit: angle %.1f %%, torque %.1f %%\n", v.angle.fit_percent, v.torque.fit_percent);
  EXPECT_GE(v.angle.fit_percent, 90.0);
  EXPECT_GE(v.torque.fit_percent, 90.0);
}

TEST(PlantFitTest, ChamberPressuresDetermineTheViscousFriction) {
  const ExperimentData fit_data = runOnElbow(prbs(1.0, 8, prbsClockSamplesForBand(30.0, kT), 1, kT), 11, true);
  const ExperimentData held_out = runOnElbow(schroederMultisine(1.0, 0.25, 30.0, 4.0, 1, kT).signal, 12, true);
  ASSERT_EQ(fit_data.tau_hydraulic_nm.size(), fit_data.q_rad.size());
  const GreyModel truth = plantGroups(fit_data);

  const FitResult fit = fitFromACorner(fit_data, truth);
  EXPECT_EQ(fit.model.delay_samples, kLatency);
  for (int i : {kFlowGain, kStiffness, kLeakage, kInertia, kLoadTorque, kViscous, kCoulomb}) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_NEAR(fit.model.value[k], truth.value[k], 0.10 * truth.value[k]) << greyParamName(i);
  }
  ValidationThresholds thresholds;
  const ModelValidation v = validateModel(fit.model, held_out, thresholds);
  std::printf("held-out fit: angle %.1f %%, torque %.1f %%\n", v.angle.fit_percent, v.torque.fit_percent);
  EXPECT_GE(v.angle.fit_percent, 90.0);
  EXPECT_GE(v.torque.fit_percent, 90.0);
}

}  // namespace
}  // namespace fullarm::identification
