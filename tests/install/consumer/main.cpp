// A user's program built against an installed fullarm: load the installed default model,
// compute gravity torques, write a report, and pass a record through a ring into an encoded LCM
// message (the installed lcm-gen headers and the LCM library).
#include <cstdio>
#include <filesystem>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/hil/log_records.hpp"
#include "fullarm/hil/spsc_ring.hpp"
#include "fullarm/reports/report.hpp"

int main() {
  const fullarm::arm::ArmModel model =
      fullarm::arm::loadArmModel(std::filesystem::path(FULLARM_CONFIG_DIR) / "dts_master.yaml");
  fullarm::arm::ArmData data(model);
  fullarm::arm::computeGravityTorques(model, data, model.defaultPosture());
  fullarm::reports::Report report("consumer", "consumer");
  report.setVerdict(true, "built against the installed package");
  report.addHeadlineNumber("shoulder_gravity_nm", "Shoulder gravity torque", data.tau_gravity[0], "N·m");
  report.write(std::filesystem::temp_directory_path() / "fullarm_consumer_report");
  std::printf("consumer: %d joints, shoulder gravity torque %.3f N m\n", model.numJoints(), data.tau_gravity[0]);

  fullarm::hil::SpscRing<fullarm::hil::JointStateRecord> ring(4);
  fullarm::hil::JointStateRecord record;
  record.num_joints = 1;
  record.q_rad[0] = 0.5;
  fullarm::hil::JointStateRecord out;
  const bool passed = ring.tryPush(record) && ring.tryPop(out);
  const fullarm_lcm::joint_state_t message = fullarm::hil::toMessage(out);
  std::vector<unsigned char> bytes(static_cast<std::size_t>(message.getEncodedSize()));
  const int encoded = message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  fullarm_lcm::joint_state_t decoded{};
  const bool round_trip = decoded.decode(bytes.data(), 0, encoded) == encoded && decoded.q_rad.at(0) == 0.5;
  std::printf("consumer: joint_state_t of %d bytes through the ring and back: %s\n", encoded,
              passed && round_trip ? "ok" : "FAILED");
  return model.numJoints() == 10 && passed && round_trip ? 0 : 1;
}
