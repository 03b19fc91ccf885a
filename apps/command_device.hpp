#pragma once
// The I/O device of a command that drives the arm outside the haptic loop (`fullarm identify`,
// `fullarm gravity --io`): the back-end built as `fullarm run` builds it (hil::IoBackend), with
// the loop configuration's period, latency, safety policy and integrator and the channel map.

#include <Eigen/Core>
#include <cstdint>
#include <ctime>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/hil_config.hpp"
#include "fullarm/hil/io_backend.hpp"
#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::app {

/// The back-ends a command can run its experiments on, by name.
inline constexpr const char* kCommandIoNames[] = {"sim", "fakedaq", "comedi", "lcm"};

/// "sim", "fakedaq", "comedi" or "lcm" as a back-end.
/// @throws core::ConfigError naming --io for any other name
[[nodiscard]] hil::IoKind commandIoKind(const std::string& name);

/// A device and everything it is built from.
struct CommandDevice {
  hil::HilConfig loop;       ///< the loop configuration (period, latency, safety, integrator)
  plant::PlantConfig plant;  ///< the simulated DTS (sim, fakedaq)
  hil::DaqConfig daq;        ///< the channel map (fakedaq, comedi)
  std::unique_ptr<hil::IoBackend> backend;
  /// lcm: what the plant node said it serves (its joints and period are the device's); empty for
  /// the other back-ends.
  std::optional<hil::IoNodeInfo> node;
  /// lcm: the node's URL (the default when none was given), for messages; empty otherwise.
  std::string lcm_url;
  /// Called before every read: waits for the next control period on the real-time clock for
  /// the real board and for an LCM node that says it serves real hardware (a simulated device,
  /// here or behind an LCM plant node, advances one period per read and needs none); false when
  /// the wait came too late to keep the period (PeriodClock).
  std::function<bool()> pace;
};

/// Paces a loop at a fixed period on CLOCK_MONOTONIC (absolute deadlines). The first call starts
/// the clock; each later call waits for the next deadline and returns false when it woke more
/// than half a period after it (the loop or the wake-up stalled: the readings no longer come a
/// period apart) or the clock could not be waited on. After a late call the deadlines restart
/// from the current time rather than catching up in a burst.
class PeriodClock {
 public:
  /// @throws std::invalid_argument for a period that is not finite and positive
  explicit PeriodClock(double period_s);
  [[nodiscard]] bool operator()();
  /// Calls that found their deadline more than half a period past.
  [[nodiscard]] long overruns() const { return overruns_; }

 private:
  long period_ns_;
  timespec next_{};
  bool started_ = false;
  long overruns_ = 0;
};

/// Builds the device of `kind` (sim, fakedaq, comedi or lcm; the arm at `posture` for the
/// simulated ones, its sensors' noise from `seed`), configured (a board that cannot be opened, or
/// an LCM plant node that does not answer at `lcm_url`, is reported here, before anything moves).
/// Empty file names take the shipped defaults.
/// `only_joint` (a model joint name; empty: every joint) makes a simulated device serve that
/// joint alone: the simulated DTS locks the others at the posture (the real arm cannot) and the
/// channel map keeps that joint's channels only. The real board always serves every joint; an
/// LCM plant node (`fullarm plant serve`) serves the joints of its plant file, which `plant`
/// must match (its posture and noise are the node's own: `posture` and `seed` are not used): the
/// device refuses a node serving other joints or another period, and a node with a scripted user
/// strapped in is refused here (the experiments assume that nobody moves the arm).
/// @throws core::ConfigError for bad files (a loop period other than `period_s` names the loop
///   file's control_period_s); hil::DeviceError when the device cannot be opened, or (lcm) the
///   node serves other joints or another period, or has a scripted user strapped in
[[nodiscard]] std::unique_ptr<CommandDevice> openCommandDevice(
    hil::IoKind kind, const arm::ArmModel& model, const plant::PlantConfig& plant, const Eigen::VectorXd& posture,
    std::uint64_t seed, const std::string& daq_config, const std::string& hil_config, double period_s,
    const std::string& only_joint = {}, const std::string& lcm_url = {});

/// --confirm-arm-motion against what an LCM plant node says it serves (nothing to check for the
/// other back-ends): when the command moves the arm (`moves`) on a node serving the real arm, the
/// option is required, the message naming the node and saying `why`; on a node serving a
/// simulated arm the option is refused.
/// @param required_with what the option is required with, for the message ("--io lcm on a node
///   serving the real arm")
/// @throws core::ConfigError naming --confirm-arm-motion
void checkNodeArmMotion(const CommandDevice& device, bool moves, bool confirmed, const std::string& required_with,
                        const std::string& why);

}  // namespace fullarm::app
