// The channel map and the converter arithmetic: codeToVolts / voltsToCode against comedilib's own
// comedi_to_phys / comedi_from_phys (bit for bit), the DTS count rule against the arm model's, and
// the loader's errors.

#include <comedilib.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include "fullarm/arm/sensors.hpp"
#include "fullarm/core/config_error.hpp"
#include "hil_fixture.hpp"

namespace fullarm::hil {
namespace {

TEST(Converters, MatchComedilibBitForBit) {
  std::mt19937 rng(7);
  for (const ConverterRange range : {ConverterRange{-10.0, 10.0, 4095}, ConverterRange{-10.0, 10.0, 65535},
                                     ConverterRange{-5.0, 5.0, 65535}, ConverterRange{0.0, 5.0, 4095}}) {
    comedi_range cr{range.min_v, range.max_v, UNIT_volt};
    comedi_set_global_oor_behavior(COMEDI_OOR_NAN);
    for (std::uint32_t code = 0; code <= range.maxdata; code += (range.maxdata > 5000 ? 13 : 1)) {
      const double ours = codeToVolts(code, range, true);
      const double theirs = comedi_to_phys(code, &cr, range.maxdata);
      if (std::isnan(theirs)) {
        EXPECT_TRUE(std::isnan(ours)) << code;
      } else {
        EXPECT_EQ(ours, theirs) << code;
      }
    }
    EXPECT_TRUE(std::isnan(codeToVolts(0, range, true)));
    EXPECT_TRUE(std::isnan(codeToVolts(range.maxdata, range, true)));
    comedi_set_global_oor_behavior(COMEDI_OOR_NUMBER);
    EXPECT_EQ(codeToVolts(range.maxdata, range, false), comedi_to_phys(range.maxdata, &cr, range.maxdata));
    std::uniform_real_distribution<double> volts(range.min_v - 1.0, range.max_v + 1.0);
    for (int i = 0; i < 20000; ++i) {
      const double v = volts(rng);
      EXPECT_EQ(voltsToCode(v, range), comedi_from_phys(v, &cr, range.maxdata)) << v;
    }
  }
}

TEST(DaqConfig, TheShippedMapReadsTheDtsCountRuleBitForBit) {
  const DaqConfig& map = test::daqConfig();
  ASSERT_EQ(map.joints.size(), 7u);
  for (const DaqJoint& j : map.joints) {
    const arm::Joint& joint = test::model().joints[static_cast<std::size_t>(test::model().jointIndex(j.name))];
    for (int code = 1; code < 4095; code += 7) {
      EXPECT_EQ(channelToPhysical(j.potentiometer.calibration, static_cast<std::uint32_t>(code), map.fake_ai),
                arm::potentiometerAngle(joint.potentiometer, code))
          << j.name << " code " << code;
      EXPECT_EQ(channelToPhysical(j.load_cell.calibration, static_cast<std::uint32_t>(code), map.fake_ai),
                arm::torqueSensorTorque(joint.torque_sensor, code))
          << j.name << " code " << code;
    }
    // Comedi reports the range ends as out of range.
    EXPECT_TRUE(std::isnan(channelToPhysical(j.potentiometer.calibration, 0, map.fake_ai)));
    EXPECT_TRUE(std::isnan(channelToPhysical(j.load_cell.calibration, 4095, map.fake_ai)));
  }
}

std::string shippedText() {
  std::ifstream in(arm::test::sourcePath("config/dts_daq.yaml"));
  return std::string(std::istreambuf_iterator<char>(in), {});
}

void expectError(const std::string& text, const std::string& key, const std::string& what) {
  try {
    (void)parseDaqConfig(text, "map.yaml", test::model());
    FAIL() << "expected an error at " << key;
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("map.yaml"), std::string::npos) << e.what();
    EXPECT_NE(e.keyPath().find(key), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  return at == std::string::npos ? text : text.replace(at, from.size(), to);
}

TEST(DaqConfig, ErrorsNameTheFileTheKeyAndTheValue) {
  const std::string text = shippedText();
  EXPECT_NO_THROW((void)parseDaqConfig(text, "map.yaml", test::model()));
  expectError(replaced(text, "name: R_EB", "name: R_ELBOW"), "joints[3].name", "R_ELBOW");
  expectError(replaced(text, "load_cell: {channel: 11", "load_cell: {channel: 2"), "joints[3].load_cell.channel",
              "used twice");
  expectError(replaced(text, "type: linear, scale: 1.0", "type: counts, scale: 1.0"), "joints[0].valve", "linear");
  expectError(replaced(text, "enable_channel: 0", "enable_channel: -1"), "board.enable_channel", ">= 0");
  expectError(replaced(text, "ai_range: 0", "ai_range: 0\n  spare: 1"), "board.spare", "");
  expectError(replaced(text, "maxdata: 4095", "maxdata: 0"), "fake_board.analog_input.maxdata", "positive");
}

// The inverse that the fake DAQ puts on an input: every code in the range reads back as itself,
// a value reads back within half a code of itself, and a value beyond the range reads as the
// range end, out of range.
TEST(DaqConfig, InputCodesInvertTheCalibration) {
  const ConverterRange range{-10.0, 10.0, 4095};
  ChannelCalibration linear;
  linear.kind = ChannelCalibration::Kind::kLinear;
  linear.scale = 2.5e6;  // a 0-10 V, 0-25 MPa transducer
  linear.offset = 1.0e5;
  ChannelCalibration counts;
  counts.kind = ChannelCalibration::Kind::kCounts;
  counts.slope_per_count = -0.0486667;
  counts.offset_counts = -2047;
  counts.offset = 0.25;
  for (const ChannelCalibration& cal : {linear, counts}) {
    const double lsb =
        cal.kind == ChannelCalibration::Kind::kLinear ? cal.scale * 20.0 / 4095.0 : std::abs(cal.slope_per_count);
    for (std::uint32_t code = 1; code < range.maxdata; ++code) {
      const double value = channelToPhysical(cal, code, range);
      ASSERT_EQ(physicalToInputCode(cal, value, range), code);
      ASSERT_EQ(physicalToInputCode(cal, value + 0.49 * lsb, range), code);
      ASSERT_EQ(physicalToInputCode(cal, value - 0.49 * lsb, range), code);
    }
    const double beyond = 1e3 * lsb * 4095.0;
    for (const double v : {beyond, -beyond}) {
      const std::uint32_t code = physicalToInputCode(cal, v, range);
      EXPECT_TRUE(code == 0 || code == range.maxdata) << v;
      EXPECT_TRUE(std::isnan(channelToPhysical(cal, code, range))) << v;
    }
    EXPECT_TRUE(std::isnan(channelToPhysical(cal, physicalToInputCode(cal, std::nan(""), range), range)));
  }
}

// Chamber pressure channels: optional, both or neither, checked like the others.
TEST(DaqConfig, PressureChannelsComeInPairsAndAreCheckedLikeTheOthers) {
  const std::string text = shippedText();
  const std::string elbow_valve = "valve: {channel: 3, calibration: {type: linear, scale: 1.0, offset: 0.0}}";
  const std::string pa = "\n    pressure_a: {channel: 7, calibration: {type: linear, scale: 2.5e6, offset: 0.0}}";
  const std::string pb = "\n    pressure_b: {channel: 15, calibration: {type: linear, scale: 2.5e6, offset: 0.0}}";
  const DaqConfig map = parseDaqConfig(replaced(text, elbow_valve, elbow_valve + pa + pb), "map.yaml", test::model());
  for (std::size_t k = 0; k < map.joints.size(); ++k) EXPECT_EQ(map.joints[k].hasPressures(), k == 3) << k;
  EXPECT_EQ(map.joints[3].pressure_a.channel, 7);
  EXPECT_EQ(map.joints[3].pressure_b.channel, 15);
  EXPECT_EQ(map.joints[3].pressure_b.calibration.scale, 2.5e6);
  EXPECT_FALSE(parseDaqConfig(text, "map.yaml", test::model()).joints[3].hasPressures());

  expectError(replaced(text, elbow_valve, elbow_valve + pa), "joints[3].pressure_b", "both chambers");
  expectError(replaced(text, elbow_valve, elbow_valve + pb), "joints[3].pressure_a", "both chambers");
  expectError(replaced(text, elbow_valve, elbow_valve + replaced(pa, "channel: 7", "channel: 3") + pb),
              "joints[3].pressure_a.channel", "used twice");
  expectError(replaced(text, elbow_valve, elbow_valve + pa + replaced(pb, "channel: 15", "channel: 16")),
              "joints[3].pressure_b.channel", "below fake_board.analog_input_channels");
  expectError(replaced(text, elbow_valve, elbow_valve + replaced(pa, "scale: 2.5e6", "scale: .nan") + pb),
              "joints[3].pressure_a.calibration.scale", "finite");
}

}  // namespace
}  // namespace fullarm::hil
