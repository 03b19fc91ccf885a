#pragma once
// The I/O device of a run, by back-end (private to the hil module).

#include <memory>

#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/hil_config.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/simulated_arm.hpp"

namespace fullarm::hil {

/// sim: a SimIoDevice on `arm`; fakedaq: the comedi back-end on the fake DAQ wired to `arm`;
/// comedi: the comedi back-end on the board of `daq` (`arm` unused).
/// @throws std::runtime_error when the board cannot be opened or does not match the map
std::unique_ptr<IoDevice> makeRunDevice(IoKind io, SimulatedArm* arm, const DaqConfig& daq, const arm::ArmModel& model,
                                        const HilConfig& config);

}  // namespace fullarm::hil
