#include "fullarm/hil/node_description.hpp"

#include <cmath>
#include <filesystem>
#include <string>

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
  if (info.simulated && !plant.empty()) {
    // The file's name as printable ASCII (the protocol's strings are), cut to leave room for the
    // hash, which is what a tick side compares.
    std::string name = plant.filename().string();
    for (char& c : name) {
      const auto b = static_cast<unsigned char>(c);
      if (b < 0x20 || b > 0x7E) c = '?';
    }
    constexpr std::size_t kHashPart = 8 + 64;  // " sha256 " and 64 hex digits
    if (name.size() + kHashPart > kMaxNodePlantChars) name.resize(kMaxNodePlantChars - kHashPart);
    info.plant = name + " sha256 " + sha256File(plant);
  }
  return info;
}

}  // namespace fullarm::hil
