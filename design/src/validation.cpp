#include "fullarm/design/validation.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <exception>
#include <mutex>
#include <sstream>
#include <thread>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/random.hpp"
#include "fullarm/core/yaml_reader.hpp"
#include "fullarm/plant/joint_params.hpp"

namespace fullarm::design {
namespace {

constexpr int kSchemaVersion = 1;
constexpr int kMaxSamples = 1000000;
constexpr int kMaxDelaySamples = 20;

std::string show(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

// A {min, max} map with lo <= min <= max <= hi.
UniformRange readRange(const core::YamlMap& parent, std::string_view key, double lo, double hi, std::string_view unit) {
  const core::YamlMap m = parent.map(key);
  UniformRange r{m.number("min", unit), m.number("max", unit)};
  m.finish();
  if (!(r.min >= lo && r.min <= hi)) {
    m.fail("min", "value " + show(r.min) + " is out of range: expected [" + show(lo) + ", " + show(hi) + "]");
  }
  if (!(r.max >= r.min && r.max <= hi)) {
    m.fail("max", "value " + show(r.max) + " is out of range: expected [min = " + show(r.min) + ", " + show(hi) + "]");
  }
  return r;
}

bool readBool(const core::YamlMap& m, std::string_view key) {
  const std::string v = m.string(key);
  if (v == "true") return true;
  if (v == "false") return false;
  m.fail(key, "'" + v + "': expected true or false");
}

ValidationConfig build(const core::YamlMap& root, const std::filesystem::path& source) {
  ValidationConfig c;
  c.source = source;
  if (root.integer("schema_version") != kSchemaVersion) root.fail("schema_version", "expected 1");
  c.samples = root.integer("samples");
  if (c.samples < 1 || c.samples > kMaxSamples) {
    root.fail("samples", "value " + std::to_string(c.samples) + ": expected 1 to " + std::to_string(kMaxSamples));
  }
  const int seed = root.integer("seed");
  if (seed < 0) root.fail("seed", "expected a seed >= 0");
  c.seed = static_cast<std::uint64_t>(seed);

  const core::YamlMap user = root.map("user");
  c.user.stiffness_nm_per_rad = user.number("stiffness_nm_per_rad", "N m/rad");
  c.user.damping_nms_per_rad = user.number("damping_nms_per_rad", "N m s/rad");
  c.user.inertia_kgm2 = user.number("inertia_kgm2", "kg m^2");
  for (const auto& [key, v] :
       {std::pair{"stiffness_nm_per_rad", c.user.stiffness_nm_per_rad},
        std::pair{"damping_nms_per_rad", c.user.damping_nms_per_rad}, std::pair{"inertia_kgm2", c.user.inertia_kgm2}}) {
    if (!(v >= 0.0)) user.fail(key, "value " + show(v) + ": expected >= 0");
  }
  user.finish();

  const core::YamlMap wall = root.map("wall");
  c.wall.enabled = true;
  c.wall.stiffness_nm_per_rad = wall.number("stiffness_nm_per_rad", "N m/rad");
  c.wall.damping_nms_per_rad = wall.number("damping_nms_per_rad", "N m s/rad");
  if (!(c.wall.stiffness_nm_per_rad > 0.0)) wall.fail("stiffness_nm_per_rad", "expected a wall stiffness > 0");
  if (!(c.wall.damping_nms_per_rad >= 0.0)) wall.fail("damping_nms_per_rad", "expected a wall damping >= 0");
  wall.finish();

  c.oscillation_speed_radps = root.number("oscillation_speed_radps", "rad/s");
  if (!(c.oscillation_speed_radps > 0.0)) root.fail("oscillation_speed_radps", "expected a threshold > 0");

  const core::YamlMap lin = root.map("linear");
  c.linear.max_peak_sensitivity = lin.number("max_peak_sensitivity");
  if (!(c.linear.max_peak_sensitivity > 1.0)) lin.fail("max_peak_sensitivity", "expected a bound > 1");
  c.linear.gate_peak_sensitivity = readBool(lin, "gate_peak_sensitivity");
  c.linear.gate_sector = readBool(lin, "gate_sector");
  c.linear.gate_passivity = readBool(lin, "gate_passivity");
  lin.finish();

  const core::YamlMap u = root.map("uncertainty");
  UncertaintyRanges& r = c.ranges;
  r.bulk_modulus_scale = readRange(u, "bulk_modulus_scale", 0.05, 20.0, "factor");
  r.valve_gain_scale = readRange(u, "valve_gain_scale", 0.05, 20.0, "factor");
  r.friction_scale = readRange(u, "friction_scale", 0.0, 20.0, "factor");
  r.inertia_scale = readRange(u, "inertia_scale", 0.05, 20.0, "factor");
  r.user_stiffness_nm_per_rad = readRange(u, "user_stiffness_nm_per_rad", 0.0, 1e5, "N m/rad");
  r.user_damping_nms_per_rad = readRange(u, "user_damping_nms_per_rad", 0.0, 1e4, "N m s/rad");
  const core::YamlMap d = u.map("delay_samples");
  r.delay_min_samples = d.integer("min");
  r.delay_max_samples = d.integer("max");
  d.finish();
  if (r.delay_min_samples < 0 || r.delay_min_samples > kMaxDelaySamples) {
    d.fail("min", "expected 0 to " + std::to_string(kMaxDelaySamples) + " samples");
  }
  if (r.delay_max_samples < r.delay_min_samples || r.delay_max_samples > kMaxDelaySamples) {
    d.fail("max", "expected min to " + std::to_string(kMaxDelaySamples) + " samples");
  }
  u.finish();
  root.finish();
  return c;
}

ValidationConfig withLines(const core::YamlMap& root, const std::filesystem::path& source) {
  return core::withKeyPathLines(root, [&] { return build(root, source); });
}

}  // namespace

ValidationConfig parseValidationConfig(std::string_view yaml_text, const std::filesystem::path& source) {
  return withLines(core::YamlMap::parse(yaml_text, source), source);
}

ValidationConfig loadValidationConfig(const std::filesystem::path& file) {
  return withLines(core::YamlMap::load(file), file);
}

std::filesystem::path defaultValidationConfigPath() {
  return core::defaultConfigPath("dts_validation.yaml");
}

double runSeverity(const ClosedLoopResult& r, double threshold) noexcept {
  const double speed = std::max(r.free_hold_speed_rms_radps, r.contact_hold_speed_rms_radps) / threshold;
  if (!r.acceptable()) return 1.0 + speed;
  return std::min(speed, 1.0);
}

void parallelFor(int jobs, int threads, const std::function<void(int)>& job) {
  if (threads <= 0) threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  threads = std::max(1, std::min(threads, jobs));
  std::atomic<int> next{0};
  std::exception_ptr error;
  std::mutex error_mutex;
  auto worker = [&] {
    for (int i = next++; i < jobs; i = next++) {
      try {
        job(i);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(static_cast<std::size_t>(threads - 1));
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

JointScenario validationScenario(const JointScenario& nominal, const ValidationConfig& config) {
  JointScenario b = nominal;
  b.load.inertia_kgm2 += config.user.inertia_kgm2 - b.user.inertia_kgm2;
  b.user = config.user;
  b.wall = config.wall;
  b.oscillation_speed_radps = config.oscillation_speed_radps;
  return b;
}

std::vector<JointMonteCarlo> runMonteCarlo(const std::vector<JointScenario>& nominal, const ValidationConfig& config,
                                           int threads, core::Progress* progress) {
  std::vector<JointScenario> bases = nominal;
  std::vector<JointMonteCarlo> out(bases.size());
  for (std::size_t j = 0; j < bases.size(); ++j) {
    JointScenario& b = bases[j];
    b = validationScenario(b, config);
    out[j].joint_name = b.joint_name;
    out[j].runs.resize(static_cast<std::size_t>(config.samples));
  }
  const int per_joint = config.samples;
  core::Progress& report = core::progressOrQuiet(progress);
  report.begin("validate: Monte-Carlo runs", bases.size() * static_cast<std::size_t>(per_joint));
  parallelFor(static_cast<int>(bases.size()) * per_joint, threads, [&](int job) {
    const int j = job / per_joint;
    const int i = job % per_joint;
    MonteCarloRun& run = out[static_cast<std::size_t>(j)].runs[static_cast<std::size_t>(i)];
    run.sample =
        drawVariation(config.ranges, config.seed, core::nameSlot(bases[static_cast<std::size_t>(j)].joint_name), i);
    run.result = simulateJoint(variationScenario(bases[static_cast<std::size_t>(j)], run.sample));
    run.severity = runSeverity(run.result, config.oscillation_speed_radps);
    report.advance();
  });
  std::size_t failed = 0;
  for (JointMonteCarlo& m : out) {
    for (int i = 0; i < static_cast<int>(m.runs.size()); ++i) {
      const MonteCarloRun& run = m.runs[static_cast<std::size_t>(i)];
      if (!run.result.acceptable()) ++m.failures;
      if (run.result.sluggish) ++m.sluggish;
      if (run.result.acceptable() && !run.result.wall_reached) ++m.wall_not_reached;
      if (m.worst < 0 || run.severity > m.runs[static_cast<std::size_t>(m.worst)].severity) m.worst = i;
    }
    failed += static_cast<std::size_t>(m.failures);
  }
  report.end(std::to_string(failed) + " of " + std::to_string(bases.size() * static_cast<std::size_t>(per_joint)) +
             " runs failed");
  return out;
}

}  // namespace fullarm::design
