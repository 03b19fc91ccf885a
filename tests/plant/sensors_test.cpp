// Sensor models: the load cell reads the torque transmitted to the link (not the actuator
// torque), calibration and quantisation as in fullarm::arm, exact first-order filtering, seeded noise.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/sensors.hpp"
#include "plant_fixture.hpp"

namespace fullarm::plant {
namespace {

// Joint pushed into its stop by the valve while the user and contact push too: at rest the
// link balances gravity, user and contact, so the load cell reads g(q) - tau_user - tau_contact
// (fullarm::arm gravity), while the actuator torque also carries the stop force.
TEST(PlantSensors, LoadCellReadsTransmittedTorqueNotActuatorTorque) {
  const arm::ArmModel& model = test::dtsModel();
  JointParams p = test::dtsPlant().joints[3];  // R_EB
  p.sensor_noise = {};
  ArmPlant plant;
  plant.configure(model, {p}, model.defaultPosture(), UserArmParams{}, test::dtsPlant().solver);
  PlantCommand cmd = PlantCommand::zero(1);
  cmd.command[0] = 3.0;
  cmd.tau_user_nm[0] = 4.0;
  cmd.tau_contact_nm[0] = -1.5;
  for (int k = 0; k < 1500; ++k) ASSERT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
  const JointState s = plant.state(0);
  ASSERT_GT(s.q_rad, p.max_rad);  // resting on the stop
  EXPECT_LT(std::abs(s.qd_radps), 1e-4);
  Eigen::VectorXd q = model.defaultPosture();
  q[3] = s.q_rad;
  arm::ArmData data(model);
  arm::computeGravityTorques(model, data, q);
  const double expected = data.tau_gravity[3] - 4.0 + 1.5;
  EXPECT_NEAR(plant.transmittedTorque(0), expected, 1e-3 * (1.0 + std::abs(expected)));
  EXPECT_GT(std::abs(plant.hydraulicTorque(0) - expected), 1.0);  // the stop carries the rest
  // Reading: quantised with the arm model's calibration, within half a count.
  const double resolution = std::abs(p.torque_sensor.slope_nm_per_count);
  EXPECT_NEAR(plant.measurement(0).tau_nm, plant.transmittedTorque(0), 0.5 * resolution + 1e-12);
  EXPECT_NEAR(plant.measurement(0).q_rad, s.q_rad, 0.5 * arm::potentiometerResolution(p.potentiometer) + 1e-12);
  EXPECT_EQ(plant.measurement(0).tau_counts,
            arm::quantizeCode(arm::torqueSensorCounts(p.torque_sensor, plant.transmittedTorque(0)), 12));
}

// First-order filter: y_k = x (1 - exp(-2 pi f k dt)) for a step x (exact ZOH discretisation).
TEST(PlantSensors, LoadCellFilterFollowsFirstOrderStepResponse) {
  JointParams p = test::dtsPlant().joints[3];
  p.sensor_noise = {};
  p.sensor_noise.torque_filter_hz = 20.0;
  JointSensorState state;
  GaussianNoise noise(1);
  (void)sampleJointSensors(p, state, noise, 1.0, 0.0, 1e-3);  // initialise at 0 N m
  const double resolution = std::abs(p.torque_sensor.slope_nm_per_count);
  for (int k = 1; k <= 50; ++k) {
    const JointMeasurement m = sampleJointSensors(p, state, noise, 1.0, 10.0, 1e-3);
    const double expected = 10.0 * (1.0 - std::exp(-2.0 * std::numbers::pi * 20.0 * k * 1e-3));
    EXPECT_NEAR(state.torque_filtered_nm, expected, 1e-9) << k;
    EXPECT_NEAR(m.tau_nm, expected, 0.5 * resolution + 1e-12) << k;
  }
}

TEST(PlantSensors, NoiseIsSeededAndHasTheRequestedSpread) {
  GaussianNoise a(42), b(42), c(43);
  double sum = 0.0;
  double sum2 = 0.0;
  bool differs = false;
  constexpr int kSamples = 200000;
  for (int i = 0; i < kSamples; ++i) {
    const double x = a.next();
    EXPECT_EQ(x, b.next());
    differs = differs || x != c.next();
    sum += x;
    sum2 += x * x;
  }
  EXPECT_TRUE(differs);
  const double mean = sum / kSamples;
  const double var = sum2 / kSamples - mean * mean;
  EXPECT_NEAR(mean, 0.0, 5.0 / std::sqrt(kSamples));  // 5 sigma
  EXPECT_NEAR(var, 1.0, 5.0 * std::sqrt(2.0 / kSamples));
}

TEST(PlantSensors, RunsAreDeterministicForASeed) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  auto run = [&](std::uint64_t seed) {
    ArmPlant plant;
    plant.configure(model, {config.joints[3]}, model.defaultPosture(), UserArmParams{}, config.solver, seed);
    PlantCommand cmd = PlantCommand::zero(1);
    std::vector<int> counts;
    for (int k = 0; k < 200; ++k) {
      cmd.command[0] = 2.0 * std::sin(k * 0.05);
      EXPECT_TRUE(plant.step(1e-3, cmd).ok());
      counts.push_back(plant.measurement(0).tau_counts);
      counts.push_back(plant.measurement(0).q_counts);
    }
    return counts;
  };
  EXPECT_EQ(run(5), run(5));
  EXPECT_NE(run(5), run(6));
}

}  // namespace
}  // namespace fullarm::plant
