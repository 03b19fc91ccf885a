// Sensor models: the load cell reads the torque transmitted to the link (not the actuator
// torque), calibration and quantisation as in fullarm::arm, exact first-order filtering, seeded noise.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

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

// Pressure transducers: an ADC of pressure_bits over [0, full scale] that saturates at both ends,
// within half a count of the pressure without noise, and the requested spread with it.
TEST(PlantSensors, PressureTransducersQuantiseOverTheirFullScaleAndSaturate) {
  JointParams p = test::dtsPlant().joints[3];
  p.sensor_noise = {};
  GaussianNoise noise(3);
  JointMeasurement none;
  samplePressureSensors(p, noise, 1.0e6, 2.0e6, none);  // no transducers: nothing read
  EXPECT_FALSE(none.pressures);
  EXPECT_EQ(none.p_a_pa, 0.0);
  p.sensor_noise.pressure_full_scale_pa = 25.0e6;
  p.sensor_noise.pressure_bits = 12;
  const double count = 25.0e6 / 4095.0;
  for (double pa : {0.0, 1.234e6, 10.3e6, 20.7e6, 25.0e6}) {
    JointMeasurement m;
    samplePressureSensors(p, noise, pa, 25.0e6 - pa, m);
    EXPECT_TRUE(m.pressures);
    EXPECT_NEAR(m.p_a_pa, pa, 0.5 * count + 1e-6) << pa;
    EXPECT_NEAR(m.p_b_pa, 25.0e6 - pa, 0.5 * count + 1e-6) << pa;
    EXPECT_NEAR(std::remainder(m.p_a_pa, count), 0.0, 1e-6) << "not a whole count";
  }
  JointMeasurement out;
  samplePressureSensors(p, noise, -0.5e6, 40.0e6, out);  // below vacuum gauge, above full scale
  EXPECT_EQ(out.p_a_pa, 0.0);
  EXPECT_NEAR(out.p_b_pa, 25.0e6, 1e-6);

  p.sensor_noise.pressure_bits = 24;  // counts of 1.5 Pa: the noise shows through
  p.sensor_noise.pressure_noise_pa = 1.0e4;
  double sum = 0.0, sum2 = 0.0;
  constexpr int kSamples = 20000;
  for (int i = 0; i < kSamples; ++i) {
    JointMeasurement m;
    samplePressureSensors(p, noise, 10.0e6, 10.0e6, m);
    sum += m.p_a_pa - 10.0e6;
    sum2 += (m.p_a_pa - 10.0e6) * (m.p_a_pa - 10.0e6);
  }
  const double mean = sum / kSamples;
  EXPECT_NEAR(mean, 0.0, 5.0 * 1.0e4 / std::sqrt(kSamples));
  EXPECT_NEAR(std::sqrt(sum2 / kSamples - mean * mean), 1.0e4, 0.05 * 1.0e4);
}

// The plant reads its chambers through the transducers (the readings within a count and six
// sigma of the noise of the true chamber pressures), and adding them leaves the angle and
// load-cell readings of a seeded run unchanged.
TEST(PlantSensors, PressureReadingsFollowTheChambersAndLeaveTheOtherReadingsAlone) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  auto run = [&](bool transducers) {
    JointParams p = config.joints[3];
    if (transducers) {
      p.sensor_noise.pressure_full_scale_pa = 25.0e6;
      p.sensor_noise.pressure_bits = 16;
      p.sensor_noise.pressure_noise_pa = 1.0e3;
    }
    ArmPlant plant;
    plant.configure(model, {p}, model.defaultPosture(), UserArmParams{}, config.solver, 9);
    PlantCommand cmd = PlantCommand::zero(1);
    std::vector<int> counts;
    double worst = 0.0;
    for (int k = 0; k < 300; ++k) {
      cmd.command[0] = 1.5 * std::sin(k * 0.04);
      EXPECT_TRUE(plant.step(1e-3, cmd).ok());
      const JointMeasurement& m = plant.measurement(0);
      counts.push_back(m.tau_counts);
      counts.push_back(m.q_counts);
      EXPECT_EQ(m.pressures, transducers);
      if (transducers) {
        const JointState s = plant.state(0);
        worst = std::max({worst, std::abs(m.p_a_pa - s.p_a_pa), std::abs(m.p_b_pa - s.p_b_pa)});
      }
    }
    if (transducers) {
      // 6 sigma of the noise plus half a 16-bit count.
      EXPECT_LT(worst, 6.0e3 + 0.5 * 25.0e6 / 65535.0);
    }
    return counts;
  };
  EXPECT_EQ(run(true), run(false));
}

}  // namespace
}  // namespace fullarm::plant
