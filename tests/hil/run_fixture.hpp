#pragma once
// Options of test runs on the shipped configuration (source tree paths).

#include "arm_test_util.hpp"
#include "fullarm/hil/run.hpp"

namespace fullarm::hil::test {

inline RunOptions shippedRun(double duration_s, haptics::RenderMode mode = haptics::RenderMode::kFullArm) {
  RunOptions o;
  o.duration_s = duration_s;
  o.mode = mode;
  o.scene = arm::test::sourcePath("scenes/valve_wall.yaml");
  o.user = arm::test::sourcePath("config/user_reach_valve.yaml");
  o.arm_config = arm::test::sourcePath("config/dts_master.yaml");
  o.plant_config = arm::test::sourcePath("config/dts_plant.yaml");
  o.gains_config = arm::test::sourcePath("config/dts_gains.yaml");
  o.haptics_config = arm::test::sourcePath("config/haptics.yaml");
  o.hil_config = arm::test::sourcePath("config/hil.yaml");
  o.daq_config = arm::test::sourcePath("config/dts_daq.yaml");
  return o;
}

}  // namespace fullarm::hil::test
