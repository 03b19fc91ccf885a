#include "local_command.hpp"

namespace fullarm::app {

RunCommandOptions localDefaults() {
  RunCommandOptions o;
  o.io = "lcm";
  o.search = "lcm";
  o.out_dir = "out/local";
  return o;
}

CLI::App* addLocalCommand(CLI::App& app, RunCommandOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "local",
      "The local node of the split run: the 1 kHz tick against an I/O device (default: the plant node over LCM), "
      "minima from `fullarm global` over LCM; writes what `fullarm run` writes");
  declareRunOptions(*cmd, o, table, RunFlavour::kLocal);
  return cmd;
}

int runLocal(const RunCommandOptions& o, const std::string& command_line) {
  RunCommandOptions local = o;
  local.search = "lcm";
  return runRun(local, command_line, "local");
}

}  // namespace fullarm::app
