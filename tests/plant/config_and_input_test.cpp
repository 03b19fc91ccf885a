// Plant YAML (strict reading, clear errors), joint names, and the command CSV reader.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "config_text.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/signals.hpp"
#include "plant_fixture.hpp"

namespace fullarm::plant {
namespace {

std::string defaultText() {
  return testing::fileText(defaultPlantConfigPath());
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  return testing::replacedFirst(std::move(text), from, to);
}

// Expects a core::ConfigError whose key path and message contain the given fragments and which
// carries a line number.
void expectConfigError(const std::string& text, const std::string& key_fragment, const std::string& message_fragment) {
  testing::expectConfigError([&] { (void)parsePlantConfig(text, "test_plant.yaml", test::dtsModel()); },
                             "test_plant.yaml", key_fragment, message_fragment);
}

TEST(PlantConfig, DefaultFileLoadsWithArmGeometry) {
  const PlantConfig& c = test::dtsPlant();
  ASSERT_EQ(c.joints.size(), 7u);
  const JointParams& eb = c.joints[static_cast<std::size_t>(findPlantJoint(c, "EB"))];
  const arm::Joint& model_eb = test::dtsModel().joints[3];
  EXPECT_EQ(eb.name, "R_EB");
  EXPECT_EQ(eb.actuator.kind, ActuatorKind::kCylinder);
  EXPECT_EQ(eb.actuator.lever.moment_arm_m, model_eb.actuator.moment_arm_m);
  EXPECT_EQ(eb.min_rad, model_eb.limits.min_rad);
  EXPECT_EQ(eb.torque_sensor.slope_nm_per_count, model_eb.torque_sensor.slope_nm_per_count);
  EXPECT_EQ(c.joints[2].actuator.kind, ActuatorKind::kRotaryVane);  // R_HR
  EXPECT_EQ(findPlantJoint(c, "R_EB"), findPlantJoint(c, "EB"));
}

// solver.integrator is optional (CVODES, the reference, when absent) and checked when given.
TEST(PlantConfig, IntegratorIsSelectable) {
  EXPECT_EQ(test::dtsPlant().solver.integrator, IntegratorKind::kCvodes);
  const std::string rodas =
      replaced(defaultText(), "  jacobian: analytic\n", "  jacobian: analytic\n  integrator: rodas3\n");
  EXPECT_EQ(parsePlantConfig(rodas, "test_plant.yaml", test::dtsModel()).solver.integrator, IntegratorKind::kRodas3);
  const std::string rodas4 =
      replaced(defaultText(), "  jacobian: analytic\n", "  jacobian: analytic\n  integrator: rodas4\n");
  EXPECT_EQ(parsePlantConfig(rodas4, "test_plant.yaml", test::dtsModel()).solver.integrator, IntegratorKind::kRodas4);
  const std::string ros34pw2 =
      replaced(defaultText(), "  jacobian: analytic\n", "  jacobian: analytic\n  integrator: ros34pw2\n");
  EXPECT_EQ(parsePlantConfig(ros34pw2, "test_plant.yaml", test::dtsModel()).solver.integrator,
            IntegratorKind::kRos34pw2);
  expectConfigError(replaced(defaultText(), "  jacobian: analytic\n", "  jacobian: analytic\n  integrator: euler\n"),
                    "solver.integrator", "expected cvodes, rodas3, rodas4 or ros34pw2");
}

TEST(PlantConfig, UnknownJointNameIsAClearError) {
  try {
    (void)findPlantJoint(test::dtsPlant(), "ELBOW");
    FAIL() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown joint name 'ELBOW'"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("EB"), std::string::npos) << e.what();
  }
  expectConfigError(replaced(defaultText(), "name: R_EB", "name: R_ELBOW"), "joints[3].name", "unknown joint name");
}

TEST(PlantConfig, BadYamlGivesFileLineAndKeyPath) {
  const std::string text = defaultText();
  expectConfigError(replaced(text, "oil_bulk_modulus_pa: 1.4e9", "oil_bulk_modulus_pa: -1.4e9"),
                    "fluid.oil_bulk_modulus_pa", "out of range");
  expectConfigError(replaced(text, "  rtol: 1.0e-4", "  rtol: 1.0e-4\n  rtoll: 1.0"), "solver.rtoll", "");
  expectConfigError(replaced(text, "jacobian: analytic", "jacobian: guess"), "solver.jacobian",
                    "analytic or finite_difference");
  expectConfigError(replaced(text, "input_mode: valve_voltage", "input_mode: current"), "joints[0].input_mode",
                    "valve_voltage or torque_loop");
  // R_EB is a cylinder in the arm model.
  const std::size_t eb = text.find("name: R_EB");
  std::string vane = text;
  vane.replace(vane.find("type: cylinder, piston_area_a_m2: 9.4e-5, piston_area_b_m2: 9.4e-5", eb),
               std::string("type: cylinder, piston_area_a_m2: 9.4e-5, piston_area_b_m2: 9.4e-5").size(),
               "type: rotary_vane, displacement_m3_per_rad: 2.5e-6");
  expectConfigError(vane, "joints[3].actuator.type", "expected cylinder");
  // A semantic check deep in a joint names the joint's key path.
  std::string bad_valve = text;
  bad_valve.replace(bad_valve.find("damping_ratio: 0.7", eb), std::string("damping_ratio: 0.7").size(),
                    "damping_ratio: 0.0");
  expectConfigError(bad_valve, "joints[3].valve.damping_ratio", "expected");
  // Missing key.
  expectConfigError(replaced(text, "  atol_spool: 1.0e-4\n", ""), "solver", "atol_spool");
}

// Pressure transducers are optional per joint; given, the three keys come together and are checked.
TEST(PlantConfig, PressureTransducerKeysAreCheckedAndNameTheJoint) {
  const std::string text = defaultText();
  const std::string sensors = "torque_bias_nm: 0.0, torque_filter_hz: 200.0";
  const std::size_t eb = text.find("name: R_EB");
  const auto withElbow = [&](const std::string& extra) {
    std::string t = text;
    t.replace(t.find(sensors, eb), sensors.size(), sensors + extra);
    return t;
  };
  const PlantConfig ok =
      parsePlantConfig(withElbow(", pressure_full_scale_pa: 25.0e6, pressure_bits: 12, pressure_noise_pa: 1.0e4"),
                       "p.yaml", test::dtsModel());
  EXPECT_EQ(ok.joints[3].sensor_noise.pressure_full_scale_pa, 25.0e6);
  EXPECT_EQ(ok.joints[3].sensor_noise.pressure_bits, 12);
  EXPECT_EQ(ok.joints[3].sensor_noise.pressure_noise_pa, 1.0e4);
  EXPECT_EQ(ok.joints[2].sensor_noise.pressure_full_scale_pa, 0.0);  // the others have none
  expectConfigError(withElbow(", pressure_full_scale_pa: 25.0e6"), "joints[3].sensors", "pressure_bits");
  expectConfigError(withElbow(", pressure_full_scale_pa: 1.0e6, pressure_bits: 12, pressure_noise_pa: 0"),
                    "joints[3].sensors.pressure_full_scale_pa", "at least the supply pressure");
  expectConfigError(withElbow(", pressure_full_scale_pa: .nan, pressure_bits: 12, pressure_noise_pa: 0"),
                    "joints[3].sensors.pressure_full_scale_pa", "");
  expectConfigError(withElbow(", pressure_full_scale_pa: 25.0e6, pressure_bits: 40, pressure_noise_pa: 0"),
                    "joints[3].sensors.pressure_bits", "[8, 24]");
  expectConfigError(withElbow(", pressure_full_scale_pa: 25.0e6, pressure_bits: 12, pressure_noise_pa: -1"),
                    "joints[3].sensors.pressure_noise_pa", ">= 0");
  expectConfigError(withElbow(", pressure_bits: 12"), "joints[3].sensors.pressure_bits", "");
}

TEST(PlantConfig, StepBeforeConfigureIsNotConfigured) {
  ArmPlant plant;
  const core::RtStatus status = plant.step(1e-3, PlantCommand::zero(1));
  EXPECT_EQ(status.code, core::RtCode::kNotConfigured);
  EXPECT_EQ(status.faults, core::kFaultNotConfigured);
}

TEST(PlantConfig, SyntaxErrorIsAConfigError) {
  EXPECT_THROW((void)parsePlantConfig("joints: [", "broken.yaml", test::dtsModel()), core::ConfigError);
  EXPECT_THROW((void)loadPlantConfig("/nonexistent/plant.yaml", test::dtsModel()), core::ConfigError);
}

class CommandCsv : public ::testing::Test {
 protected:
  std::filesystem::path write(const std::string& text) {
    const std::filesystem::path p = std::filesystem::temp_directory_path() /
                                    ("fullarm_plant_csv_" + std::to_string(counter_++) + "_" +
                                     ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".csv");
    std::ofstream(p) << text;
    files_.push_back(p);
    return p;
  }
  void TearDown() override {
    for (const auto& f : files_) std::filesystem::remove(f);
  }
  void expectError(const std::string& text, const std::string& fragment) {
    const std::filesystem::path p = write(text);
    try {
      (void)loadCommandCsv(p);
      ADD_FAILURE() << "no error for: " << text;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(p.string()), std::string::npos) << e.what();
    }
  }
  int counter_ = 0;
  std::vector<std::filesystem::path> files_;
};

TEST_F(CommandCsv, ReadsAndHoldsValues) {
  const CommandTable t = loadCommandCsv(write("time_s,command\n0.0,1.5\n0.5, -2\n1.0,3e-1\n"));
  ASSERT_EQ(t.time_s.size(), 3u);
  EXPECT_EQ(t.valueAt(0, 0.25), 1.5);
  EXPECT_EQ(t.valueAt(0, 0.5), -2.0);
  EXPECT_EQ(t.valueAt(0, 7.0), 0.3);
  EXPECT_EQ(t.valueAt(0, -1.0), 1.5);
}

TEST_F(CommandCsv, MalformedFilesGiveLineNumbers) {
  expectError("", "empty file");
  expectError("t,u\n0,1\n", ":1: bad header");
  expectError("time_s,command\n0,1\n0.1,abc\n", ":3: 'abc' is not a finite number");
  expectError("time_s,command\n0,1\n0.1\n", ":3: expected 2 values");
  expectError("time_s,command\n0,1\n0,2\n", ":3: time_s must increase");
  expectError("time_s,command\n0,nan\n", ":2: 'nan' is not a finite number");
  expectError("time_s,command\n", "no data rows");
  EXPECT_THROW((void)loadCommandCsv("/nonexistent/commands.csv"), std::runtime_error);
}

// Against the analytic value: a constant offset c on a sampled sine of amplitude A (whole
// periods: mean 0, RMS A / sqrt(2)) is an RMS difference of |c|, ratio |c| sqrt(2) / A.
TEST(Signals, NormalisedRmsDifferenceOfAnOffsetSine) {
  std::vector<double> ref;
  std::vector<double> shifted;
  for (int k = 0; k < 1000; ++k) {
    ref.push_back(3.0 + 2.0 * std::sin(2.0 * std::numbers::pi * 5.0 * k / 1000.0));
    shifted.push_back(ref.back() + 0.01);
  }
  EXPECT_NEAR(normalisedRmsDifference(ref, shifted), 0.01 * std::sqrt(2.0) / 2.0, 1e-12);
  EXPECT_EQ(normalisedRmsDifference(ref, ref), 0.0);
  EXPECT_THROW((void)normalisedRmsDifference(ref, std::vector<double>(999, 0.0)), std::invalid_argument);
  EXPECT_THROW((void)normalisedRmsDifference({}, {}), std::invalid_argument);
  EXPECT_THROW((void)normalisedRmsDifference(std::vector<double>(10, 1.0), std::vector<double>(10, 2.0)),
               std::invalid_argument);
}

TEST(Signals, ChirpStartsAtStartFrequencyAndParsesNames) {
  SignalParams s;
  s.amplitude = 2.0;
  s.start_hz = 1.0;
  s.stop_hz = 1.0;  // constant frequency: a plain sine
  EXPECT_NEAR(signalValue(s, 0.25), 2.0, 1e-12);
  EXPECT_EQ(parseSignalKind("multisine"), SignalKind::kMultisine);
  EXPECT_THROW((void)parseSignalKind("noise"), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::plant
