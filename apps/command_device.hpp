#pragma once
// The I/O device of a command that drives the arm outside the haptic loop (`fullarm identify`,
// `fullarm gravity --io`): the back-end built as `fullarm run` builds it (hil::IoBackend), with
// the loop configuration's period, latency, safety policy and integrator and the channel map.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/hil_config.hpp"
#include "fullarm/hil/io_backend.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::app {

/// The back-ends a command can run its experiments on, by name.
inline constexpr const char* kCommandIoNames[] = {"sim", "fakedaq", "comedi"};

/// "sim", "fakedaq" or "comedi" as a back-end.
/// @throws core::ConfigError naming --io for any other name
[[nodiscard]] hil::IoKind commandIoKind(const std::string& name);

/// A device and everything it is built from.
struct CommandDevice {
  hil::HilConfig loop;     ///< the loop configuration (period, latency, safety, integrator)
  plant::PlantConfig plant;  ///< the simulated DTS (sim, fakedaq)
  hil::DaqConfig daq;        ///< the channel map (fakedaq, comedi)
  std::unique_ptr<hil::IoBackend> backend;
  /// Called before every read: waits for the next control period on the real-time clock for
  /// the real board (a simulated device advances one period per read and needs none).
  std::function<void()> pace;
};

/// Builds the device of `kind` (sim, fakedaq or comedi; the arm at `posture` for the simulated
/// ones, its sensors' noise from `seed`), configured (a board that cannot be opened is reported
/// here, before anything moves). Empty file names take the shipped defaults.
/// `only_joint` (a model joint name; empty: every joint) makes a simulated device serve that
/// joint alone: the simulated DTS locks the others at the posture (the real arm cannot) and the
/// channel map keeps that joint's channels only. The real board always serves every joint.
/// @throws core::ConfigError for bad files (a loop period other than `period_s` names the loop
///   file's control_period_s); hil::DeviceError when the device cannot be opened
[[nodiscard]] std::unique_ptr<CommandDevice> openCommandDevice(hil::IoKind kind, const arm::ArmModel& model,
                                                               const plant::PlantConfig& plant,
                                                               const Eigen::VectorXd& posture, std::uint64_t seed,
                                                               const std::string& daq_config,
                                                               const std::string& hil_config, double period_s,
                                                               const std::string& only_joint = {});

}  // namespace fullarm::app
