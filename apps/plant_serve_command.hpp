#pragma once
// `fullarm plant serve`: the simulated DTS as an LCM I/O node for `fullarm run`, `fullarm identify` and
// `fullarm gravity` with `--io lcm`.

#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

#include "cli_options.hpp"
#include "loop_options.hpp"

namespace fullarm::app {

/// Options of `fullarm plant serve`.
struct PlantServeOptions {
  std::string lcm_url;    ///< empty: the default URL (udpm, ttl=0: this machine only)
  LoopFileOptions files;  ///< scene and configuration files
  std::string user;       ///< scripted user YAML (default config/user_reach_valve.yaml)
  bool no_user = false;   ///< nobody strapped in (identification, gravity holds)
  std::string start_posture = "ready";
  std::uint64_t seed = 1;
  double watchdog_s = 0.1;    ///< no command for this long: safe outputs
  double idle_exit_s = 30.0;  ///< no command for this long: stop serving
};

/// Adds `serve` under the existing `plant` command of `app`; returns it.
CLI::App* addPlantServeCommand(CLI::App& app, PlantServeOptions& options, OptionTable& table);
/// Serves until idle for --idle-exit or until SIGINT / SIGTERM; prints the node's log.
/// @return 0 when serving ended with the outputs safe (always, unless the device failed)
int runPlantServe(const PlantServeOptions& options, std::ostream& out);

}  // namespace fullarm::app
