#pragma once
/// @file
/// The loop's configuration (config/hil.yaml; schema in docs/hil.md, "Loop configuration"):
/// the control period, the I/O policy, the global search's schedule, the real-time loop's
/// settings and the safety supervisor's parameters.

#include <filesystem>
#include <string_view>

#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/supervisor.hpp"
#include "fullarm/plant/arm_plant.hpp"

namespace fullarm::hil {

struct HilConfig {
  std::filesystem::path source;
  double control_period_s = 1e-3;
  // I/O.
  int latency_samples = 1;  ///< simulated back-ends: readings this many periods old
  IoSafetyParams io_safety;
  plant::IntegratorKind sim_integrator = plant::IntegratorKind::kRodas3;
  // Global search.
  int global_period_ticks = 10;     ///< the search runs every this many ticks (100 Hz at 1 kHz)
  int delivery_delay_ticks = 5;     ///< lockstep: a result is adopted this many ticks after its query
  // Real-time loop.
  int overrun_limit = 10;           ///< consecutive overruns before the supervisor trips
  int realtime_priority = 80;       ///< SCHED_FIFO priority of the tick thread (when permitted)
  int search_priority = 60;         ///< SCHED_FIFO priority of the global-search thread
  int tick_cpu = 1;                 ///< CPU the tick thread is pinned to (-1: none)
  double heartbeat_period_s = 0.01; ///< how often the supervising side beats
  SupervisorParams supervisor;
};

/// Reads and checks a loop configuration (strict).
/// @throws core::ConfigError naming the file, line, key path and what was expected
[[nodiscard]] HilConfig loadHilConfig(const std::filesystem::path& file);
[[nodiscard]] HilConfig parseHilConfig(std::string_view yaml_text, const std::filesystem::path& file);
/// core::defaultConfigPath("hil.yaml").
[[nodiscard]] std::filesystem::path defaultHilConfigPath();

}  // namespace fullarm::hil
