// A user's program built against an installed fullarm: load the installed default model,
// compute gravity torques, write a report.
#include <cstdio>
#include <filesystem>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
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
  return model.numJoints() == 10 ? 0 : 1;
}
