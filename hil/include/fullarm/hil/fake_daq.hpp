#pragma once
/// @file
/// The fake DAQ: an in-process stand-in for the comedilib calls the comedi back-end makes, with
/// Comedi's semantics (subdevices, channels, ranges, maxdata, readings at the range ends reported
/// out of range, outputs that hold when the process stops), wired to the simulated DTS. The
/// comedi back-end's own source (channel map, calibration, enable line) is compiled a second time
/// against these functions instead of comedilib's (docs/hil.md, "The fake DAQ"), so the real
/// back-end's logic runs in CI without a board.
///
/// The board's state (the codes on every channel, the digital lines, when the enable line last
/// changed) is plain data, kept in memory or in a file mapped into memory, so that a test can
/// kill the process driving the board and still look at it: the analog outputs hold their last
/// codes, as a real board's do, and the model of the external hardware watchdog
/// (amplifierEnabled) drops the amplifier enable once the enable line has stopped toggling.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>

#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/simulated_arm.hpp"

namespace fullarm::hil {

/// Channels of the fake board at most.
inline constexpr int kFakeDaqMaxAnalogInputs = 32;
inline constexpr int kFakeDaqMaxAnalogOutputs = 16;
inline constexpr int kFakeDaqMaxDigitalLines = 32;

/// The board's state: trivially copyable, the same bytes in memory and in its file.
struct FakeDaqState {
  std::uint64_t magic = 0;  ///< kFakeDaqMagic once initialised
  ConverterRange ai{};
  ConverterRange ao{};
  int ai_channels = 0;
  int ao_channels = 0;
  int dio_channels = 0;
  std::uint32_t ai_codes[kFakeDaqMaxAnalogInputs] = {};
  std::uint32_t ao_codes[kFakeDaqMaxAnalogOutputs] = {};
  std::uint32_t dio_levels = 0;     ///< bit per line
  std::uint32_t dio_outputs = 0;    ///< bit per line configured as an output
  std::int64_t enable_changed_ns = 0;      ///< CLOCK_MONOTONIC time the enable line last changed
  std::uint64_t enable_changed_period = 0; ///< simulated period it last changed
  std::uint64_t enable_changes = 0;
  std::uint64_t periods = 0;               ///< simulated periods advanced
  int enable_line = 0;
  std::int32_t writer_pid = 0;             ///< process that last wrote an output
};

inline constexpr std::uint64_t kFakeDaqMagic = 0x6661'6b65'6461'7131ull;  // "fakedaq1"

/// A fake board. The comedilib stand-in finds it by its device name (DaqConfig::device).
class FakeDaqBoard {
 public:
  /// A board in memory (`state_file` empty) or in `state_file` (created, or replaced), with the
  /// converters and channel counts of the channel map's fake_board section, registered under
  /// map.device.
  /// @throws std::runtime_error naming the file when it cannot be created or mapped
  FakeDaqBoard(const DaqConfig& map, const std::filesystem::path& state_file = {});
  ~FakeDaqBoard();
  FakeDaqBoard(const FakeDaqBoard&) = delete;
  FakeDaqBoard& operator=(const FakeDaqBoard&) = delete;

  [[nodiscard]] FakeDaqState& state() noexcept { return *state_; }
  [[nodiscard]] const FakeDaqState& state() const noexcept { return *state_; }
  [[nodiscard]] const std::string& device() const noexcept { return device_; }

  /// Maps an existing board file read-only (the test's view after the driving process died).
  /// @throws std::runtime_error naming the file
  [[nodiscard]] static std::shared_ptr<const FakeDaqState> inspect(const std::filesystem::path& state_file);

 private:
  std::string device_;
  std::filesystem::path file_;
  FakeDaqState* state_ = nullptr;
  std::unique_ptr<FakeDaqState> memory_;
  std::size_t mapped_bytes_ = 0;
};

/// The external hardware watchdog of the rig (docs/hil.md, "What the rig must provide"): the
/// valve amplifiers are enabled while the enable line has changed within `timeout_s`, by
/// CLOCK_MONOTONIC `now_ns`. @rt
[[nodiscard]] bool amplifierEnabled(const FakeDaqState& state, std::int64_t now_ns, double timeout_s) noexcept;
/// The same in simulated periods (lockstep runs): within `timeout_periods` periods. @rt
[[nodiscard]] bool amplifierEnabledPeriods(const FakeDaqState& state, std::uint64_t timeout_periods) noexcept;

/// The fake DAQ wired to the simulated DTS: before each read of the comedi back-end, one control
/// period passes: the analog outputs' codes become volts (the amplifier's input, zero when the
/// watchdog has dropped the enable), the simulated arm advances with them, and its sensors' codes
/// appear on the analog inputs (potentiometer and load cell channels of the map).
class FakeDaqRig {
 public:
  /// @param watchdog_timeout_s the hardware watchdog's timeout
  FakeDaqRig(FakeDaqBoard& board, SimulatedArm& arm, const DaqConfig& map, double watchdog_timeout_s);
  /// One period of the world between two reads. Allocation-free, unbounded time (the plant).
  core::RtStatus advance() noexcept;
  /// Fills the analog inputs from the arm's current readings (also done by advance()).
  void publishReadings() noexcept;

 private:
  FakeDaqBoard& board_;
  SimulatedArm& arm_;
  const DaqConfig& map_;
  std::uint64_t timeout_periods_;
  IoVector volts_;
};

/// The comedi back-end on the fake board of `map.device` wired through `rig` (not owned; both
/// outlive the device). Its joints are the channel map's.
[[nodiscard]] std::unique_ptr<IoDevice> makeFakeDaqIoDevice(const DaqConfig& map, const arm::ArmModel& model,
                                                            double period_s, const IoSafetyParams& safety,
                                                            FakeDaqRig* rig);

/// The comedi back-end on the real board of `map.device` (comedilib).
[[nodiscard]] std::unique_ptr<IoDevice> makeComediIoDevice(const DaqConfig& map, const arm::ArmModel& model,
                                                           double period_s, const IoSafetyParams& safety);

}  // namespace fullarm::hil
