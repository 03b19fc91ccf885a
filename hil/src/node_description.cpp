#include "fullarm/hil/node_description.hpp"

#include <cmath>
#include <filesystem>

#include "fullarm/hil/run_recording.hpp"

namespace fullarm::hil {

IoNodeInfo describeSessionDevice(HilSession& session) {
  IoNodeInfo info;
  const IoDevice& device = session.device();
  for (int k = 0; k < device.joints().size(); ++k) {
    info.joint_names.push_back(session.model().joints[static_cast<std::size_t>(device.joints().modelIndex(k))].name);
  }
  info.period_us = static_cast<std::int32_t>(std::lround(device.period() * 1e6));
  info.simulated = session.simulatedArm() != nullptr;
  info.scripted_user = session.user() != nullptr;
  const std::filesystem::path& plant = session.options().plant_config;
  if (info.simulated && !plant.empty()) info.plant = plant.filename().string() + " sha256 " + sha256File(plant);
  return info;
}

}  // namespace fullarm::hil
