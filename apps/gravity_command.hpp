#pragma once
// `fullarm gravity`: the arm's gravity load fitted physically consistent, to the DTS reference's
// identified torques or to a static-holds log, written as an arm YAML.

#include <CLI/CLI.hpp>
#include <optional>
#include <ostream>
#include <string>

#include "cli_options.hpp"
#include "fullarm/core/progress.hpp"

namespace fullarm::app {

/// Options of `fullarm gravity`.
struct GravityOptions {
  std::string arm_config;    ///< --config (default: dts_master.yaml)
  std::string holds;         ///< --holds: a static-holds log to fit (default: the reference's torques)
  std::string io;            ///< --io: take the static holds on this device (sim | fakedaq | comedi | lcm) and fit them
  std::string plant_config;  ///< --plant: the simulated DTS of sim and fakedaq (default: dts_plant.yaml)
  std::string sim_arm;       ///< --sim-arm: the arm the simulated DTS moves (default: --config)
  std::string daq_config;    ///< --daq-config: the channel map of fakedaq and comedi
  std::string hil_config;    ///< --hil-config: the loop configuration of the device
  std::string lcm_url;       ///< --lcm-url: the plant node of lcm (empty: the default URL)
  /// --postures: random postures of the fit to the reference (default 400) or held on the
  /// device (default 16)
  std::optional<int> postures;
  int seed = 1;  ///< --seed: which random postures (and the simulated sensors' noise)
  /// --confirm-arm-motion: the operator has cleared the real arm's workspace (--io comedi moves
  /// it to random postures with no check for self-collision or its surroundings)
  bool confirm_arm_motion = false;
  std::string out_dir = "out/gravity";
  /// Progress of the holds (a step per hold; null: none).
  core::Progress* progress = nullptr;
};

/// Adds `gravity` to `app`.
CLI::App* addGravityCommand(CLI::App& app, GravityOptions& options, OptionTable& table);

/// Fits, prints the residual per joint, writes `arm.yaml` (the arm file with the fitted masses
/// and centres of mass) and `gravity.csv` (the per-joint table) into --out. With --io it first
/// holds the postures on the device and writes their log, `holds.csv` (what --holds reads),
/// reporting a progress step per hold.
/// @return 0 when written; 1 when the holds on the device stopped early (a limit, a fault: the
///   holds taken are in holds.csv, nothing is fitted)
/// @throws core::ConfigError for bad input (a malformed holds log names the line); OutputError
int runGravity(const GravityOptions& options, std::ostream& out);

}  // namespace fullarm::app
