#pragma once
// `fullarm local`: the local node of the split run: the tick against an I/O device, with its
// minima from the global node `fullarm global` over LCM.

#include <CLI/CLI.hpp>
#include <string>

#include "cli_options.hpp"
#include "run_command.hpp"

namespace fullarm::app {

/// The options of `fullarm local`: the run's, with the search always the global node's and the
/// I/O remote by default (the plant node `fullarm plant serve`).
[[nodiscard]] RunCommandOptions localDefaults();
/// Adds `local`; returns it. `options` should start from localDefaults().
CLI::App* addLocalCommand(CLI::App& app, RunCommandOptions& options, OptionTable& table);
/// Runs the local node: `fullarm run` with the global search over LCM, the same outputs.
/// @return as runRun
int runLocal(const RunCommandOptions& options, const std::string& command_line);

}  // namespace fullarm::app
