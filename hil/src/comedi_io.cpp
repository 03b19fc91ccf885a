// The comedi back-end on a real board: comedi_backend.ipp against comedilib.

#include "comedi_api_real.hpp"
#include "fullarm/hil/fake_daq.hpp"

#define FULLARM_COMEDI_NAMESPACE comedi_board
#define FULLARM_COMEDI_API ::fullarm::hil::comedi_real_api
#include "comedi_backend.ipp"

namespace fullarm::hil {

std::unique_ptr<IoDevice> makeComediIoDevice(const DaqConfig& map, const arm::ArmModel& model, double period_s,
                                             const IoSafetyParams& safety) {
  return std::make_unique<comedi_board::ComediBackend>(map, comedi_board::mapJoints(map, model), period_s, safety,
                                                       "comedi", BoardClock{});
}

}  // namespace fullarm::hil
