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

}  // namespace
}  // namespace fullarm::hil
