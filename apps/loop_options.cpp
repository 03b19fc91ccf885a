#include "loop_options.hpp"

namespace fullarm::app {
namespace {

volatile std::sig_atomic_t g_stop_requested = 0;

extern "C" void onLoopStopSignal(int /*signal*/) {
  g_stop_requested = 1;
}

}  // namespace

void declareLoopFiles(OptionDeclarer& declare, LoopFileOptions& files) {
  declare.file("--scene", files.scene, "Scene YAML (default: scenes/valve_wall.yaml)");
  declare.file("--config", files.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--plant-config", files.plant_config, "Plant YAML (default: config/dts_plant.yaml)");
  declare.file("--gains", files.gains_config, "Gains YAML (default: config/dts_gains.yaml)");
  declare.file("--haptics-config", files.haptics_config, "Haptics YAML (default: config/haptics.yaml)");
  declare.file("--hil-config", files.hil_config, "Loop YAML (default: config/hil.yaml)");
}

void applyLoopFiles(const LoopFileOptions& files, hil::RunOptions& options) {
  options.scene = pathOr(files.scene);
  options.arm_config = pathOr(files.arm_config);
  options.plant_config = pathOr(files.plant_config);
  options.gains_config = pathOr(files.gains_config);
  options.haptics_config = pathOr(files.haptics_config);
  options.hil_config = pathOr(files.hil_config);
}

std::filesystem::path pathOr(const std::string& text) {
  return text.empty() ? std::filesystem::path() : std::filesystem::path(text);
}

StopSignalGuard::StopSignalGuard() {
  g_stop_requested = 0;
  struct sigaction sa {};
  sa.sa_handler = onLoopStopSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &old_int_);
  sigaction(SIGTERM, &sa, &old_term_);
}

StopSignalGuard::~StopSignalGuard() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
}

bool StopSignalGuard::requested() noexcept {
  return g_stop_requested != 0;
}

}  // namespace fullarm::app
