#pragma once
// The `fullarm` program as a function: its subcommands, their declared options, and the mapping
// of every outcome to an exit code (exit_codes.hpp). main() calls runFullarm(); the tests call it
// and declaredOptions() in-process.

#include <exception>
#include <ostream>
#include <string>
#include <vector>

#include "cli_options.hpp"

namespace fullarm::app {

/// Runs `fullarm args...` (args without the program name). Results go to `out`, errors and
/// progress to `err`. Never throws: an exception that escapes a command is reported on `err` and
/// mapped to kExitBadInput (configuration, scene, mesh and output errors) or kExitInternal.
int runFullarm(const std::vector<std::string>& args, std::ostream& out, std::ostream& err);

/// The exit code of a command that ended with `error`, its message written to `err`: kExitBadInput
/// for bad input the user can fix (core::ConfigError, haptics::MeshError, OutputError,
/// std::filesystem::filesystem_error), kExitInternal for anything else ("internal error").
int exitCodeForException(const std::exception_ptr& error, std::ostream& err);

/// Every option of every subcommand as declared (the table runFullarm parses with).
[[nodiscard]] OptionTable declaredOptions();

/// An option as CLI11 parses it: its subcommand path and every long name it answers to.
struct ParsedOption {
  std::string command;             ///< "plant simulate" ("" for the program's own options)
  std::vector<std::string> names;  ///< "--duration"; a flag with a negation has both names
};

/// Every option the program parses, declared or not (without --help and --version): the table
/// must hold each of them.
[[nodiscard]] std::vector<ParsedOption> parsedOptions();

}  // namespace fullarm::app
