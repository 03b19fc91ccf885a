#pragma once
/// @file
/// The channel map and calibration of a data-acquisition board (config/dts_daq.yaml; schema in
/// docs/hil.md), and the converter arithmetic of Comedi (code <-> volts over a range), shared by
/// the comedi back-end, the fake DAQ and, when asked, the simulated device: with the same
/// converter model the three turn the same codes into the same numbers, bit for bit.

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_model.hpp"

namespace fullarm::hil {

/// A converter's range (Comedi's comedi_range and maxdata).
struct ConverterRange {
  double min_v = -10.0;
  double max_v = 10.0;
  std::uint32_t maxdata = 4095;  ///< largest code
};

/// Volts of a code, with comedi_to_phys's arithmetic (the same operations in the same order).
/// With `out_of_range_nan`, the codes at the range ends (0 and maxdata) are NaN: Comedi's
/// COMEDI_OOR_NAN, which flags a saturated input. @rt
[[nodiscard]] double codeToVolts(std::uint32_t code, const ConverterRange& range, bool out_of_range_nan) noexcept;
/// Code of a voltage, with comedi_from_phys's arithmetic (rounded, clamped to [0, maxdata]). @rt
[[nodiscard]] std::uint32_t voltsToCode(double volts, const ConverterRange& range) noexcept;

/// How a channel's reading becomes a physical value.
struct ChannelCalibration {
  enum class Kind {
    kCounts,   ///< physical = (code + offset_counts) slope + offset (the DTS joint cards' rule)
    kLinear,   ///< physical = scale volts + offset, volts from the range (comedi_to_phys)
    kSoftcal,  ///< physical = scale volts + offset, volts from the board's Comedi soft calibration
  };
  Kind kind = Kind::kLinear;
  double slope_per_count = 1.0;  ///< kCounts
  double offset_counts = 0.0;    ///< kCounts
  double scale = 1.0;            ///< kLinear, kSoftcal: physical units per volt
  double offset = 0.0;           ///< every kind: added last
};

/// One analog channel of the map.
struct DaqChannel {
  int channel = -1;  ///< -1: not wired (an optional channel the map does not list)
  ChannelCalibration calibration;
};

/// The channels of one joint: three always, two more where the joint's actuator has chamber
/// pressure transducers (a rig or an arm retrofitted with them; the DTS master has none).
struct DaqJoint {
  std::string name;          ///< arm joint name
  int file_index = -1;       ///< its place in the file's `joints` list (-1: built in code)
  DaqChannel potentiometer;  ///< analog input [rad]
  DaqChannel load_cell;      ///< analog input [N m]
  DaqChannel valve;          ///< analog output [V at the valve amplifier]
  DaqChannel pressure_a;     ///< analog input [Pa, gauge], chamber A; channel -1 when not wired
  DaqChannel pressure_b;     ///< analog input [Pa, gauge], chamber B; wired exactly when A is
  [[nodiscard]] bool hasPressures() const noexcept { return pressure_a.channel >= 0; }
};

/// The board and its channel map. Constant after loadDaqConfig().
struct DaqConfig {
  std::filesystem::path source;
  std::string device = "/dev/comedi0";  ///< Comedi device file
  int ai_subdevice = -1;                ///< -1: the first analog-input subdevice
  int ao_subdevice = -1;                ///< -1: the first analog-output subdevice
  int dio_subdevice = -1;               ///< -1: the first digital-I/O subdevice
  int ai_range = 0;                     ///< Comedi range index of every input channel
  int ao_range = 0;                     ///< Comedi range index of every output channel
  int enable_channel = 0;               ///< digital line toggled every tick (hardware watchdog)
  /// Comedi soft-calibration file (channels of kind kSoftcal); empty when none is used.
  std::filesystem::path softcal_file;
  std::vector<DaqJoint> joints;  ///< one per device joint, in the arm model's order
  /// The converters of the fake DAQ (and of the simulated device when it uses this map).
  ConverterRange fake_ai{-10.0, 10.0, 4095};
  ConverterRange fake_ao{-10.0, 10.0, 65535};
  int fake_ai_channels = 16;
  int fake_ao_channels = 8;
  int fake_dio_channels = 8;
  /// The rig's hardware watchdog: the amplifiers are enabled while the enable line changed
  /// within this time [s] (fake DAQ model; the real rig's is set in its hardware).
  double fake_watchdog_timeout_s = 0.05;
};

/// Reads and checks a channel map for `model` (strict: unknown and missing keys are errors; a
/// joint the model does not know, a channel used twice, a negative channel are errors).
/// @throws core::ConfigError naming the file, line, key path and what was expected
[[nodiscard]] DaqConfig loadDaqConfig(const std::filesystem::path& file, const arm::ArmModel& model);
/// Same from text; `file` names the source in errors.
[[nodiscard]] DaqConfig parseDaqConfig(std::string_view yaml_text, const std::filesystem::path& file,
                                       const arm::ArmModel& model);
/// core::defaultConfigPath("dts_daq.yaml").
[[nodiscard]] std::filesystem::path defaultDaqConfigPath();

/// Physical value of an input channel's code read through `range`: NaN when the code is at a
/// range end (Comedi's out-of-range reading). Kinds kCounts and kLinear only (kSoftcal needs the
/// board's polynomial: the comedi back-end). @rt
[[nodiscard]] double channelToPhysical(const ChannelCalibration& cal, std::uint32_t code,
                                       const ConverterRange& range) noexcept;
/// Volts the converter must put out for the physical value `value` of an output channel
/// (kLinear: (value - offset) / scale). @rt
[[nodiscard]] double physicalToChannelVolts(const ChannelCalibration& cal, double value) noexcept;
/// The code an input channel reads when its sensor gives `value`: the inverse of
/// channelToPhysical, rounded to the nearest code and clamped to [0, maxdata] (a value beyond the
/// range reads as a range end, that is out of range). Kinds kCounts and kLinear; what the fake DAQ
/// and the simulated device put on an input channel. @rt
[[nodiscard]] std::uint32_t physicalToInputCode(const ChannelCalibration& cal, double value,
                                                const ConverterRange& range) noexcept;

}  // namespace fullarm::hil
