#include "fullarm/hil/daq_config.hpp"

#include <cmath>
#include <limits>
#include <set>

#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::hil {

double codeToVolts(std::uint32_t code, const ConverterRange& range, bool out_of_range_nan) noexcept {
  if (range.maxdata == 0) return std::numeric_limits<double>::quiet_NaN();
  if (out_of_range_nan && (code == 0 || code == range.maxdata)) return std::numeric_limits<double>::quiet_NaN();
  // comedi_to_phys: x = data; x /= maxdata; x *= (max - min); x += min.
  double x = code;
  x /= range.maxdata;
  x *= (range.max_v - range.min_v);
  x += range.min_v;
  return x;
}

std::uint32_t voltsToCode(double volts, const ConverterRange& range) noexcept {
  if (range.maxdata == 0 || !std::isfinite(volts)) return 0;
  // comedi_from_phys: s = (data - min) / (max - min) * maxdata, clamped, rounded half up.
  const double s = (volts - range.min_v) / (range.max_v - range.min_v) * range.maxdata;
  if (s < 0) return 0;
  if (s > range.maxdata) return range.maxdata;
  return static_cast<std::uint32_t>(std::floor(s + 0.5));
}

double channelToPhysical(const ChannelCalibration& cal, std::uint32_t code, const ConverterRange& range) noexcept {
  const double volts = codeToVolts(code, range, true);
  if (std::isnan(volts)) return volts;
  switch (cal.kind) {
    case ChannelCalibration::Kind::kCounts:
      return (static_cast<double>(code) + cal.offset_counts) * cal.slope_per_count + cal.offset;
    case ChannelCalibration::Kind::kLinear:
      return cal.scale * volts + cal.offset;
    case ChannelCalibration::Kind::kSoftcal:
      break;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double physicalToChannelVolts(const ChannelCalibration& cal, double value) noexcept {
  return (value - cal.offset) / cal.scale;
}

std::uint32_t physicalToInputCode(const ChannelCalibration& cal, double value, const ConverterRange& range) noexcept {
  if (cal.kind == ChannelCalibration::Kind::kCounts) {
    if (!std::isfinite(value) || range.maxdata == 0) return 0;
    const double code = std::floor((value - cal.offset) / cal.slope_per_count - cal.offset_counts + 0.5);
    if (!(code > 0.0)) return 0;
    if (code >= static_cast<double>(range.maxdata)) return range.maxdata;
    return static_cast<std::uint32_t>(code);
  }
  return voltsToCode(physicalToChannelVolts(cal, value), range);
}

namespace {

ChannelCalibration readCalibration(const core::YamlMap& m, bool output) {
  ChannelCalibration c;
  const std::string type = m.string("type");
  if (type == "counts" && !output) {
    c.kind = ChannelCalibration::Kind::kCounts;
    c.slope_per_count = m.number("slope_per_count");
    c.offset_counts = m.number("offset_counts");
    c.offset = m.number("offset");
    if (!std::isfinite(c.slope_per_count) || c.slope_per_count == 0.0) {
      m.fail("slope_per_count", "expected a finite, non-zero slope");
    }
  } else if (type == "linear" || (type == "softcal" && !output)) {
    c.kind = type == "linear" ? ChannelCalibration::Kind::kLinear : ChannelCalibration::Kind::kSoftcal;
    c.scale = m.number("scale");
    c.offset = m.number("offset");
    if (!std::isfinite(c.scale) || c.scale == 0.0) m.fail("scale", "expected a finite, non-zero scale");
  } else {
    m.fail("type", output ? "expected linear for an output channel, got '" + type + "'"
                          : "expected counts, linear or softcal, got '" + type + "'");
  }
  if (!std::isfinite(c.offset)) m.fail("offset", "expected a finite offset");
  m.finish();
  return c;
}

DaqChannel readChannel(const core::YamlMap& m, bool output) {
  DaqChannel ch;
  ch.channel = m.integer("channel");
  if (ch.channel < 0) m.fail("channel", "expected a channel number >= 0");
  ch.calibration = readCalibration(m.map("calibration"), output);
  m.finish();
  return ch;
}

ConverterRange readRange(const core::YamlMap& m) {
  ConverterRange r;
  r.min_v = m.number("min_v", "V");
  r.max_v = m.number("max_v", "V");
  const int maxdata = m.integer("maxdata");
  if (!(r.max_v > r.min_v)) m.fail("max_v", "expected max_v > min_v");
  if (maxdata <= 0) m.fail("maxdata", "expected a positive largest code");
  r.maxdata = static_cast<std::uint32_t>(maxdata);
  m.finish();
  return r;
}

int optionalSubdevice(const core::YamlMap& m, std::string_view key) {
  if (!m.has(key)) return -1;
  const std::string text = m.string(key);
  if (text == "auto") return -1;
  const int v = m.integer(key);
  if (v < 0) m.fail(key, "expected auto or a subdevice number >= 0");
  return v;
}

DaqConfig readDaqConfig(const core::YamlMap& root, const arm::ArmModel& model) {
  DaqConfig c;
  c.source = root.file();
  if (root.integer("schema_version") != 1) root.fail("schema_version", "expected 1");
  const core::YamlMap board = root.map("board");
  c.device = board.string("device");
  c.ai_subdevice = optionalSubdevice(board, "ai_subdevice");
  c.ao_subdevice = optionalSubdevice(board, "ao_subdevice");
  c.dio_subdevice = optionalSubdevice(board, "dio_subdevice");
  c.ai_range = board.integer("ai_range");
  c.ao_range = board.integer("ao_range");
  c.enable_channel = board.integer("enable_channel");
  if (c.ai_range < 0) board.fail("ai_range", "expected a range index >= 0");
  if (c.ao_range < 0) board.fail("ao_range", "expected a range index >= 0");
  if (c.enable_channel < 0) board.fail("enable_channel", "expected a digital line >= 0");
  if (const auto softcal = board.optionalString("softcal_file")) {
    c.softcal_file = *softcal;
    if (c.softcal_file.is_relative() && !c.source.empty()) c.softcal_file = c.source.parent_path() / c.softcal_file;
  }
  board.finish();

  const core::YamlMap fake = root.map("fake_board");
  c.fake_ai = readRange(fake.map("analog_input"));
  c.fake_ao = readRange(fake.map("analog_output"));
  c.fake_ai_channels = fake.integer("analog_input_channels");
  c.fake_ao_channels = fake.integer("analog_output_channels");
  c.fake_dio_channels = fake.integer("digital_channels");
  if (c.fake_ai_channels <= 0) fake.fail("analog_input_channels", "expected a positive count");
  if (c.fake_ao_channels <= 0) fake.fail("analog_output_channels", "expected a positive count");
  c.fake_watchdog_timeout_s = fake.number("watchdog_timeout_s", "s");
  if (!(c.fake_watchdog_timeout_s > 0.0) || !std::isfinite(c.fake_watchdog_timeout_s)) {
    fake.fail("watchdog_timeout_s", "expected a timeout > 0 s");
  }
  if (c.fake_dio_channels <= c.enable_channel) {
    fake.fail("digital_channels", "expected more lines than board.enable_channel");
  }
  fake.finish();

  const core::YamlList joints = root.list("joints");
  std::set<int> ai_used;
  std::set<int> ao_used;
  bool softcal_used = false;
  int previous_index = -1;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const core::YamlMap j = joints.map(i);
    DaqJoint dj;
    dj.file_index = static_cast<int>(i);
    dj.name = j.string("name");
    const int index = model.jointIndex(dj.name);
    if (index < 0) j.fail("name", "'" + dj.name + "' is not a joint of the arm model " + model.name);
    if (index <= previous_index) j.fail("name", "expected the joints in the arm model's order, each once");
    previous_index = index;
    dj.potentiometer = readChannel(j.map("potentiometer"), false);
    dj.load_cell = readChannel(j.map("load_cell"), false);
    dj.valve = readChannel(j.map("valve"), true);
    // Chamber pressure transducers: both chambers or neither.
    if (j.has("pressure_a") != j.has("pressure_b")) {
      j.fail(j.has("pressure_a") ? "pressure_b" : "pressure_a",
             "expected the pressure channels of both chambers (pressure_a and pressure_b) or of neither");
    }
    std::vector<std::pair<std::string, DaqChannel*>> inputs{{"potentiometer", &dj.potentiometer},
                                                            {"load_cell", &dj.load_cell}};
    if (j.has("pressure_a")) {
      dj.pressure_a = readChannel(j.map("pressure_a"), false);
      dj.pressure_b = readChannel(j.map("pressure_b"), false);
      inputs.emplace_back("pressure_a", &dj.pressure_a);
      inputs.emplace_back("pressure_b", &dj.pressure_b);
    }
    for (const auto& [key, ch] : inputs) {
      if (!ai_used.insert(ch->channel).second) {
        j.fail(key + ".channel", "analog input " + std::to_string(ch->channel) + " is used twice");
      }
      if (ch->channel >= c.fake_ai_channels) {
        j.fail(key + ".channel", "expected a channel below fake_board.analog_input_channels");
      }
      softcal_used = softcal_used || ch->calibration.kind == ChannelCalibration::Kind::kSoftcal;
    }
    if (!ao_used.insert(dj.valve.channel).second) {
      j.fail("valve.channel", "analog output " + std::to_string(dj.valve.channel) + " is used twice");
    }
    if (dj.valve.channel >= c.fake_ao_channels) {
      j.fail("valve.channel", "expected a channel below fake_board.analog_output_channels");
    }
    j.finish();
    c.joints.push_back(std::move(dj));
  }
  if (c.joints.empty()) root.fail("joints", "expected at least one joint");
  if (softcal_used && c.softcal_file.empty()) {
    root.fail("board.softcal_file", "a channel uses softcal calibration: name the Comedi calibration file");
  }
  root.finish();
  return c;
}

}  // namespace

DaqConfig parseDaqConfig(std::string_view yaml_text, const std::filesystem::path& file, const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, file);
  return core::withKeyPathLines(root, [&] { return readDaqConfig(root, model); });
}

DaqConfig loadDaqConfig(const std::filesystem::path& file, const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::load(file);
  return core::withKeyPathLines(root, [&] { return readDaqConfig(root, model); });
}

std::filesystem::path defaultDaqConfigPath() {
  return core::defaultConfigPath("dts_daq.yaml");
}

}  // namespace fullarm::hil
