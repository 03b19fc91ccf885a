#pragma once
// `fullarm run` (the haptic loop on a simulated, fake-DAQ or real DTS) and `fullarm replay LOG`.

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>

#include "cli_options.hpp"
#include "loop_options.hpp"

namespace fullarm::app {

/// The longest `fullarm run` accepted: every tick is kept in memory for the report and the
/// replay check.
inline constexpr double kMaxRunDuration_s = 600.0;

/// Options of `fullarm run`.
struct RunCommandOptions {
  std::string io = "sim";             ///< sim | fakedaq | comedi | lcm
  std::string search = "in-process";  ///< in-process | lcm (the global node)
  std::string lcm_url;                ///< --io lcm, --search lcm: the nodes' LCM URL (empty: the default)
  std::string mode = "full-arm";      ///< full-arm | hand-only
  LoopFileOptions files;              ///< scene and configuration files
  double duration_s = 10.0;
  std::string clock = "realtime";  ///< realtime | lockstep
  std::string user;                ///< scripted user YAML (default config/user_reach_valve.yaml)
  std::string out_dir = "out/run";
  std::uint64_t seed = 1;
  std::string daq_config;                   ///< channel map YAML (default config/dts_daq.yaml)
  std::optional<int> delivery_delay_ticks;  ///< unset: the loop configuration's
  bool no_oracle = false;
  std::string start_posture = "ready";
};

/// Which of the run's options a command declares.
enum class RunFlavour {
  kRun,    ///< `fullarm run`: every option
  kLocal,  ///< `fullarm local`: the search is the global node's (no --search), one mode at a time
};

/// Declares the run's options on `command` (`fullarm run` and `fullarm local` share them).
void declareRunOptions(CLI::App& command, RunCommandOptions& options, OptionTable& table, RunFlavour flavour);
/// Adds `run`; returns it.
CLI::App* addRunCommand(CLI::App& app, RunCommandOptions& options, OptionTable& table);
/// Runs it: the LCM log run.lcmlog, summary.json and report.html in the output folder. The
/// printed lines start with `fullarm <command_name>:`.
/// @return 0 when the run ended without a supervisor trip (and, in lockstep, without a missed
///   contact), 1 otherwise.
int runRun(const RunCommandOptions& options, const std::string& command_line, const std::string& command_name = "run");

/// Options of `fullarm replay`.
struct ReplayCommandOptions {
  std::string log;
  std::string out_dir;  ///< optional: summary.json and report.html
};

/// Adds `replay`; returns it.
CLI::App* addReplayCommand(CLI::App& app, ReplayCommandOptions& options, OptionTable& table);
/// Replays a run log through the same tick: 0 when every force, torque and valve command is
/// reproduced bit for bit, 1 otherwise; a corrupt log throws (exit 2).
int runReplay(const ReplayCommandOptions& options);

}  // namespace fullarm::app
