#include "plant_serve_command.hpp"

#include "exit_codes.hpp"
#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/node_description.hpp"
#include "fullarm/hil/run.hpp"
#include "loop_options.hpp"

namespace fullarm::app {

CLI::App* addPlantServeCommand(CLI::App& app, PlantServeOptions& o, OptionTable& table) {
  CLI::App* plant = app.get_subcommand("plant");
  CLI::App* cmd = plant->add_subcommand(
      "serve",
      "Serve the simulated DTS as an LCM I/O node for `fullarm run`, `identify` and `gravity` with `--io lcm` (each "
      "command advances it one period)");
  OptionDeclarer declare(*cmd, table);
  declare.name("--lcm-url", o.lcm_url, std::string("LCM URL (default ") + hil::kDefaultLcmUrl + ": this machine only)");
  declareLoopFiles(declare, o.files);
  CLI::Option* user = declare.file("--user", o.user, "Scripted user YAML (default: config/user_reach_valve.yaml)");
  declare
      .flag("--no-user", o.no_user,
            "Nobody strapped in: the arm moves only as commanded (for `identify` and `gravity` over LCM)")
      ->excludes(user);
  declare.name("--start-posture", o.start_posture, "Scene posture the simulated arm starts in")->capture_default_str();
  declare.integer("--seed", o.seed, "Seed of the simulated sensors' noise", 0, 2147483647);
  declare
      .number("--watchdog", o.watchdog_s, "No command for this long: safe outputs (null valves)", {0.002, 10.0, "s"})
      ->capture_default_str();
  declare
      .number("--idle-exit", o.idle_exit_s, "No command for this long (or none at all): stop serving",
              {0.01, 86400.0, "s"})
      ->capture_default_str();
  return cmd;
}

int runPlantServe(const PlantServeOptions& o, std::ostream& out) {
  hil::RunOptions ro;
  ro.io = hil::IoKind::kSim;
  ro.clock = hil::ClockKind::kLockstep;
  applyLoopFiles(o.files, ro);
  ro.user = pathOr(o.user);
  ro.scripted_user = !o.no_user;
  ro.seed = o.seed;
  ro.start_posture = o.start_posture;
  hil::HilSession session(ro);  // the simulated arm, its user and the sim device

  hil::PlantNodeOptions node_options;
  if (!o.lcm_url.empty()) node_options.url = o.lcm_url;
  node_options.info = hil::describeSessionDevice(session);
  node_options.watchdog_timeout_s = o.watchdog_s;
  node_options.idle_exit_s = o.idle_exit_s;
  node_options.on_log = [&out](const std::string& line) { out << "fullarm plant serve: " << line << std::endl; };
  hil::LcmPlantNode node(session.device(), node_options);
  hil::PlantNodeResult r;
  {
    const StopSignalGuard stop;
    r = node.serve([] { return StopSignalGuard::requested(); });
  }
  out << "fullarm plant serve: " << r.commands << " commands served, " << r.stale_commands << " stale, " << r.rejected
      << " rejected, " << r.watchdog_trips << " watchdog trips; outputs " << (r.safe_at_exit ? "safe" : "NOT safe")
      << " at exit\n";
  return r.safe_at_exit ? kExitPass : kExitFail;
}

}  // namespace fullarm::app
