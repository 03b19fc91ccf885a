#pragma once
// What the loop's commands share (`run`, `local`, `global`, `plant serve`): the input files they
// read, declared and applied in one place, and the stop signal of the commands that serve until
// stopped.

#include <signal.h>

#include <csignal>
#include <filesystem>
#include <string>

#include "cli_options.hpp"
#include "fullarm/hil/run.hpp"

namespace fullarm::app {

/// The input files every loop command reads (empty: the shipped default).
struct LoopFileOptions {
  std::string scene;  ///< scene YAML (default scenes/valve_wall.yaml)
  std::string arm_config, plant_config, gains_config, haptics_config, hil_config;
};

/// Declares --scene, --config, --plant-config, --gains, --haptics-config and --hil-config.
void declareLoopFiles(OptionDeclarer& declare, LoopFileOptions& files);
/// Puts the files into the loop's options (an empty text keeps the default).
void applyLoopFiles(const LoopFileOptions& files, hil::RunOptions& options);
/// `text` as a path; empty text is the empty path (the loop's default).
[[nodiscard]] std::filesystem::path pathOr(const std::string& text);

/// SIGINT and SIGTERM request a stop while the guard lives; the previous handlers return when it
/// ends. One guard at a time.
class StopSignalGuard {
 public:
  StopSignalGuard();
  ~StopSignalGuard();
  StopSignalGuard(const StopSignalGuard&) = delete;
  StopSignalGuard& operator=(const StopSignalGuard&) = delete;

  /// True once SIGINT or SIGTERM arrived (async-signal-safe flag).
  [[nodiscard]] static bool requested() noexcept;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

}  // namespace fullarm::app
