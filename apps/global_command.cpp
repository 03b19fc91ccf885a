#include "global_command.hpp"

#include <csignal>
#include <filesystem>

#include "exit_codes.hpp"
#include "fullarm/hil/lcm_search.hpp"
#include "fullarm/hil/run.hpp"

namespace fullarm::app {
namespace {

volatile std::sig_atomic_t g_stop = 0;

extern "C" void onGlobalStopSignal(int /*signal*/) {
  g_stop = 1;
}

std::filesystem::path pathOr(const std::string& s) {
  return s.empty() ? std::filesystem::path() : std::filesystem::path(s);
}

}  // namespace

CLI::App* addGlobalCommand(CLI::App& app, GlobalCommandOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "global", "Serve the global search as an LCM node for `fullarm run --search lcm` (one minima set per query)");
  OptionDeclarer declare(*cmd, table);
  declare.name("--lcm-url", o.lcm_url, "LCM URL (default udpm://239.255.76.67:7667?ttl=0: this machine only)");
  declare.choice("--mode", o.mode, "Haptic rendering (as the run's)", {"full-arm", "hand-only"})->capture_default_str();
  declare.file("--scene", o.scene, "Scene YAML (default: scenes/valve_wall.yaml)");
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--plant-config", o.plant_config, "Plant YAML (default: config/dts_plant.yaml)");
  declare.file("--gains", o.gains_config, "Gains YAML (default: config/dts_gains.yaml)");
  declare.file("--haptics-config", o.haptics_config, "Haptics YAML (default: config/haptics.yaml)");
  declare.file("--hil-config", o.hil_config, "Loop YAML (default: config/hil.yaml)");
  declare
      .number("--idle-exit", o.idle_exit_s, "No query for this long (or none at all): stop serving",
              {0.01, 86400.0, "s"})
      ->capture_default_str();
  return cmd;
}

int runGlobal(const GlobalCommandOptions& o, std::ostream& out) {
  hil::RunOptions ro;
  ro.clock = hil::ClockKind::kLockstep;
  ro.mode = o.mode == "hand-only" ? haptics::RenderMode::kHandOnly : haptics::RenderMode::kFullArm;
  ro.scene = pathOr(o.scene);
  ro.arm_config = pathOr(o.arm_config);
  ro.plant_config = pathOr(o.plant_config);
  ro.gains_config = pathOr(o.gains_config);
  ro.haptics_config = pathOr(o.haptics_config);
  ro.hil_config = pathOr(o.hil_config);
  const hil::HilSession session(ro, false);  // the model, the scene's world, the haptics parameters
  hil::GlobalSearchRunner search(session.model(), session.world(), session.hapticsParams());

  hil::GlobalNodeOptions node_options;
  if (!o.lcm_url.empty()) node_options.url = o.lcm_url;
  node_options.idle_exit_s = o.idle_exit_s;
  node_options.on_log = [&out](const std::string& line) { out << "fullarm global: " << line << std::endl; };
  hil::LcmGlobalNode node(search, session.model().numJoints(), node_options);
  g_stop = 0;
  const auto previous_int = std::signal(SIGINT, onGlobalStopSignal);
  const auto previous_term = std::signal(SIGTERM, onGlobalStopSignal);
  const hil::GlobalNodeResult r = node.serve([] { return g_stop != 0; });
  std::signal(SIGINT, previous_int);
  std::signal(SIGTERM, previous_term);
  out << "fullarm global: " << r.queries << " queries answered, " << r.stale << " stale, " << r.rejected
      << " rejected\n";
  return kExitPass;
}

}  // namespace fullarm::app
