#pragma once
// `fullarm global`: the global search as an LCM node for `fullarm run --search lcm`.

#include <CLI/CLI.hpp>
#include <ostream>
#include <string>

#include "cli_options.hpp"
#include "loop_options.hpp"

namespace fullarm::app {

/// Options of `fullarm global`.
struct GlobalCommandOptions {
  std::string lcm_url;            ///< empty: the default URL (udpm, ttl=0: this machine only)
  std::string mode = "full-arm";  ///< full-arm | hand-only
  LoopFileOptions files;          ///< scene and configuration files
  double idle_exit_s = 30.0;      ///< no query for this long: stop serving
};

/// Adds `global`; returns it.
CLI::App* addGlobalCommand(CLI::App& app, GlobalCommandOptions& options, OptionTable& table);
/// Serves queries until idle for --idle-exit or until SIGINT / SIGTERM; prints the node's log.
/// @return 0
int runGlobal(const GlobalCommandOptions& options, std::ostream& out);

}  // namespace fullarm::app
