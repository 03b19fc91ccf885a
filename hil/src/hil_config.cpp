#include "fullarm/hil/hil_config.hpp"

#include <cmath>

#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::hil {

namespace {

double positive(const core::YamlMap& m, std::string_view key, std::string_view unit) {
  const double v = m.number(key, unit);
  if (!(v > 0.0) || !std::isfinite(v)) m.fail(key, "expected a finite value > 0");
  return v;
}

double nonNegative(const core::YamlMap& m, std::string_view key, std::string_view unit) {
  const double v = m.number(key, unit);
  if (!(v >= 0.0) || !std::isfinite(v)) m.fail(key, "expected a finite value >= 0");
  return v;
}

int atLeast(const core::YamlMap& m, std::string_view key, int lowest) {
  const int v = m.integer(key);
  if (v < lowest) m.fail(key, "expected an integer >= " + std::to_string(lowest));
  return v;
}

HilConfig readHilConfig(const core::YamlMap& root) {
  HilConfig c;
  c.source = root.file();
  if (root.integer("schema_version") != 1) root.fail("schema_version", "expected 1");
  c.control_period_s = positive(root, "control_period_s", "s");

  const core::YamlMap io = root.map("io");
  c.latency_samples = atLeast(io, "latency_samples", 0);
  if (c.latency_samples > 15) io.fail("latency_samples", "expected at most 15 periods");
  c.io_safety.ramp_in_s = nonNegative(io, "ramp_in_s", "s");
  c.io_safety.valve_limit_v = positive(io, "valve_limit_v", "V");
  const std::string integrator = io.string("sim_integrator");
  if (integrator == "cvodes") {
    c.sim_integrator = plant::IntegratorKind::kCvodes;
  } else if (integrator == "rodas3") {
    c.sim_integrator = plant::IntegratorKind::kRodas3;
  } else if (integrator == "rodas4") {
    c.sim_integrator = plant::IntegratorKind::kRodas4;
  } else if (integrator == "ros34pw2") {
    c.sim_integrator = plant::IntegratorKind::kRos34pw2;
  } else {
    io.fail("sim_integrator", "'" + integrator + "': expected cvodes, rodas3, rodas4 or ros34pw2");
  }
  io.finish();

  const core::YamlMap search = root.map("global_search");
  c.global_period_ticks = atLeast(search, "period_ticks", 1);
  c.delivery_delay_ticks = atLeast(search, "delivery_delay_ticks", 1);
  search.finish();

  const core::YamlMap loop = root.map("realtime");
  c.overrun_limit = atLeast(loop, "overrun_limit", 1);
  c.realtime_priority = atLeast(loop, "tick_priority", 1);
  c.search_priority = atLeast(loop, "search_priority", 1);
  if (c.realtime_priority > 99) loop.fail("tick_priority", "expected a SCHED_FIFO priority 1 .. 99");
  if (c.search_priority > 99) loop.fail("search_priority", "expected a SCHED_FIFO priority 1 .. 99");
  c.tick_cpu = atLeast(loop, "tick_cpu", -1);
  c.heartbeat_period_s = positive(loop, "heartbeat_period_s", "s");
  loop.finish();

  const core::YamlMap s = root.map("supervisor");
  SupervisorParams& p = c.supervisor;
  p.position_margin_rad = nonNegative(s, "position_margin_rad", "rad");
  p.velocity_limit_factor = positive(s, "velocity_limit_factor", "");
  p.velocity_filter_hz = positive(s, "velocity_filter_hz", "Hz");
  p.max_plausible_rate_radps = positive(s, "max_plausible_rate_radps", "rad/s");
  p.torque_limit_factor = positive(s, "torque_limit_factor", "");
  p.startup_valid_s = nonNegative(s, "startup_valid_s", "s");
  p.stale_global_periods = atLeast(s, "stale_global_periods", 1);
  p.fade_s = positive(s, "fade_s", "s");
  p.max_fade_rate_nm_per_s = positive(s, "max_fade_rate_nm_per_s", "N m/s");
  p.heartbeat_timeout_s = positive(s, "heartbeat_timeout_s", "s");
  p.peer_heartbeat_timeout_s = positive(s, "peer_heartbeat_timeout_s", "s");
  s.finish();
  p.global_period_s = c.global_period_ticks * c.control_period_s;
  if (p.velocity_filter_hz >= 0.5 / c.control_period_s) {
    s.fail("velocity_filter_hz", "expected a cutoff below the Nyquist frequency of control_period_s");
  }
  if (p.heartbeat_timeout_s <= c.heartbeat_period_s) {
    s.fail("heartbeat_timeout_s", "expected a timeout longer than realtime.heartbeat_period_s");
  }
  // The contact forces fade out before communication loss puts the valves at null.
  const double faded_s = p.stale_global_periods * p.global_period_s + p.fade_s;
  if (p.peer_heartbeat_timeout_s <= faded_s) {
    s.fail("peer_heartbeat_timeout_s",
           "expected a timeout longer than the stale-minima fade (stale_global_periods x "
           "the global period + fade_s = " +
               std::to_string(faded_s) + " s)");
  }
  root.finish();
  return c;
}

}  // namespace

HilConfig parseHilConfig(std::string_view yaml_text, const std::filesystem::path& file) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, file);
  return core::withKeyPathLines(root, [&] { return readHilConfig(root); });
}

HilConfig loadHilConfig(const std::filesystem::path& file) {
  const core::YamlMap root = core::YamlMap::load(file);
  return core::withKeyPathLines(root, [&] { return readHilConfig(root); });
}

std::filesystem::path defaultHilConfigPath() {
  return core::defaultConfigPath("hil.yaml");
}

}  // namespace fullarm::hil
