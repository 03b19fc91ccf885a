#include "fullarm/hil/io_backend.hpp"

#include <stdexcept>

#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/sim_io.hpp"

namespace fullarm::hil {

const char* ioKindName(IoKind io) noexcept {
  switch (io) {
    case IoKind::kSim:
      return "sim";
    case IoKind::kFakeDaq:
      return "fakedaq";
    case IoKind::kComedi:
      return "comedi";
    case IoKind::kLcm:
      return "lcm";
  }
  return "unknown";
}

IoBackend::IoBackend(const arm::ArmModel& model, const IoBackendOptions& options) : kind_(options.io) {
  const bool simulated = options.io == IoKind::kSim || options.io == IoKind::kFakeDaq;
  const bool needs_map = options.io == IoKind::kFakeDaq || options.io == IoKind::kComedi ||
                         (options.io == IoKind::kSim && options.sim_uses_daq_converters);
  if (simulated && options.plant == nullptr) {
    throw std::invalid_argument(std::string("I/O back-end ") + ioKindName(options.io) + ": no plant to simulate");
  }
  if (needs_map && options.daq == nullptr) {
    throw std::invalid_argument(std::string("I/O back-end ") + ioKindName(options.io) + ": no channel map");
  }
  // The simulated arm lives in this process for sim and fakedaq, in the plant node for lcm.
  if (simulated) {
    arm_ = std::make_unique<SimulatedArm>(model, *options.plant, options.posture, options.period_s,
                                          options.latency_samples);
  }
  switch (options.io) {
    case IoKind::kSim: {
      SimIoOptions sim;
      if (options.sim_uses_daq_converters) sim.converters = options.daq;
      device_ = std::make_unique<SimIoDevice>(*arm_, sim, options.safety);
      break;
    }
    case IoKind::kFakeDaq:
      board_ = std::make_unique<FakeDaqBoard>(*options.daq, options.fakedaq_state_file);
      rig_ = std::make_unique<FakeDaqRig>(*board_, *arm_, *options.daq, options.daq->fake_watchdog_timeout_s);
      device_ = makeFakeDaqIoDevice(*options.daq, model, options.period_s, options.safety, rig_.get());
      break;
    case IoKind::kComedi:
      device_ = makeComediIoDevice(*options.daq, model, options.period_s, options.safety);
      break;
    case IoKind::kLcm: {
      LcmIoOptions lcm;
      if (!options.lcm_url.empty()) lcm.url = options.lcm_url;
      if (options.lcm_reply_timeout_s > 0.0) lcm.reply_timeout_s = options.lcm_reply_timeout_s;
      if (options.lcm_max_missed_replies > 0) lcm.max_missed_replies = options.lcm_max_missed_replies;
      for (int k = 0; k < options.lcm_joints.size(); ++k) {
        lcm.joint_names.push_back(model.joints[static_cast<std::size_t>(options.lcm_joints.modelIndex(k))].name);
      }
      device_ = std::make_unique<LcmIoDevice>(options.lcm_joints, options.period_s, options.safety, lcm);
      break;
    }
  }
}

IoBackend::~IoBackend() = default;

}  // namespace fullarm::hil
