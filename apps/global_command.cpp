#include "global_command.hpp"

#include "exit_codes.hpp"
#include "fullarm/hil/lcm_search.hpp"
#include "fullarm/hil/run.hpp"
#include "loop_options.hpp"

namespace fullarm::app {

CLI::App* addGlobalCommand(CLI::App& app, GlobalCommandOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "global",
      "Serve the global search as an LCM node for `fullarm local` and `fullarm run --search lcm` (a minima set per "
      "lockstep query; in real time, sets on the newest live joint state)");
  OptionDeclarer declare(*cmd, table);
  declare.name("--lcm-url", o.lcm_url, std::string("LCM URL (default ") + hil::kDefaultLcmUrl + ": this machine only)");
  declare.choice("--mode", o.mode, "Haptic rendering (as the run's)", {"full-arm", "hand-only"})->capture_default_str();
  declareLoopFiles(declare, o.files);
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
  applyLoopFiles(o.files, ro);
  const hil::HilSession session(ro, false);  // the model, the scene's world, the haptics parameters
  hil::GlobalSearchRunner search(session.model(), session.world(), session.hapticsParams());

  hil::GlobalNodeOptions node_options;
  if (!o.lcm_url.empty()) node_options.url = o.lcm_url;
  node_options.idle_exit_s = o.idle_exit_s;
  node_options.on_log = [&out](const std::string& line) { out << "fullarm global: " << line << std::endl; };
  hil::LcmGlobalNode node(search, session.model().numJoints(), node_options);
  hil::GlobalNodeResult r;
  {
    const StopSignalGuard stop;
    r = node.serve([] { return StopSignalGuard::requested(); });
  }
  out << "fullarm global: " << r.queries << " queries answered, " << r.live_states << " live joint states ("
      << r.live_sets << " sets sent), " << r.stale << " stale, " << r.rejected << " rejected\n";
  return kExitPass;
}

}  // namespace fullarm::app
