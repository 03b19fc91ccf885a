#include "run_devices.hpp"

#include <stdexcept>

#include "fullarm/hil/sim_io.hpp"

namespace fullarm::hil {

std::unique_ptr<IoDevice> makeRunDevice(IoKind io, SimulatedArm* arm, const DaqConfig& /*daq*/,
                                        const arm::ArmModel& /*model*/, const HilConfig& config) {
  switch (io) {
    case IoKind::kSim:
      return std::make_unique<SimIoDevice>(*arm, SimIoOptions{}, config.io_safety);
    case IoKind::kFakeDaq:
    case IoKind::kComedi:
      break;
  }
  throw std::runtime_error(std::string("I/O back-end ") + ioKindName(io) + " is not available in this build");
}

}  // namespace fullarm::hil
