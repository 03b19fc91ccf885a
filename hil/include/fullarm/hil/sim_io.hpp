#pragma once
/// @file
/// The `sim` I/O back-end: a SimulatedArm in-process. Each read() advances the plant by one
/// control period with the last written command held (a zero-order hold, as a DAC does) and
/// returns the reading the configured latency old; each write() quantises the command through
/// the DAC model. With a channel map (SimIoOptions::converters) the readings go through the map's
/// converters and calibrations exactly as the fake DAQ's do, so the two back-ends give the same
/// numbers bit for bit.

#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/simulated_arm.hpp"

namespace fullarm::hil {

/// Converter model of the sim back-end.
struct SimIoOptions {
  /// DAC of the valve commands when no channel map is given (16-bit, +-10 V).
  ConverterRange dac{-10.0, 10.0, 65535};
  /// Channel map whose fake-board converters and calibrations the readings and commands go
  /// through (not owned; nullptr: the plant's own readings in SI units and the DAC above).
  const DaqConfig* converters = nullptr;
};

/// Checks that the channel map `map` can wire the simulated arm `arm`: the arm's joints in order,
/// and pressure channels only on joints whose plant has chamber pressure transducers.
/// @param who names the back-end in the error
/// @throws core::ConfigError naming the map's file, the key (`joints[3].pressure_a`) and what
///   was expected
void checkChannelMapFitsArm(const DaqConfig& map, const SimulatedArm& arm, std::string_view who);

class SimIoDevice final : public IoDevice {
 public:
  /// @param arm the simulated DTS (not owned; outlives the device)
  /// @throws core::ConfigError when the channel map does not fit the arm (checkChannelMapFitsArm)
  SimIoDevice(SimulatedArm& arm, const SimIoOptions& options, const IoSafetyParams& safety);
  [[nodiscard]] std::string_view name() const noexcept override { return "sim"; }
  [[nodiscard]] SimulatedArm& simulatedArm() noexcept { return arm_; }

 private:
  void onConfigure() override;
  core::RtStatus onRead(JointSample& sample) noexcept override;
  core::RtStatus onWrite(const IoVector& valve_v, bool toggle_enable) noexcept override;

  SimulatedArm& arm_;
  SimIoOptions options_;
  IoVector held_v_;  // the DAC's output, held until the next write
};

}  // namespace fullarm::hil
