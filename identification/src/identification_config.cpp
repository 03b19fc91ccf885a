#include "fullarm/identification/identification_config.hpp"

#include <fstream>
#include <sstream>
#include <string>
#include <tuple>
#include <utility>

#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::identification {
namespace {

constexpr int kSchemaVersion = 1;

}  // namespace

IdentificationConfig parseIdentificationConfig(std::string_view yaml_text, const std::filesystem::path& source) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, source);
  return core::withKeyPathLines(root, [&] {
    IdentificationConfig c;
    c.source = source;
    if (root.integer("schema_version") != kSchemaVersion) root.fail("schema_version", "expected 1");

    const core::YamlMap model = root.map("model");
    c.coulomb_smoothing_radps = model.number("coulomb_smoothing_radps", "rad/s");
    if (!(c.coulomb_smoothing_radps > 0.0)) model.fail("coulomb_smoothing_radps", "expected > 0");
    c.stribeck_velocity_radps = model.number("stribeck_velocity_radps", "rad/s");
    if (!(c.stribeck_velocity_radps > 0.0)) model.fail("stribeck_velocity_radps", "expected > 0");
    model.finish();

    const core::YamlMap fit = root.map("fit");
    c.fit.max_delay_samples = fit.integer("max_delay_samples");
    if (c.fit.max_delay_samples < 0 || c.fit.max_delay_samples > 20) fit.fail("max_delay_samples", "expected 0..20");
    c.fit.global_samples = fit.integer("global_samples");
    if (c.fit.global_samples < 1) fit.fail("global_samples", "expected >= 1");
    c.fit.polished_candidates = fit.integer("polished_candidates");
    if (c.fit.polished_candidates < 1) fit.fail("polished_candidates", "expected >= 1");
    c.fit.max_iterations = fit.integer("max_iterations");
    if (c.fit.max_iterations < 1) fit.fail("max_iterations", "expected >= 1");
    const int seed = fit.integer("seed");
    if (seed < 0) fit.fail("seed", "expected >= 0");
    c.fit.seed = static_cast<std::uint64_t>(seed);
    const std::string jacobian = fit.string("jacobian");
    if (jacobian == "sensitivities") {
      c.fit.jacobian = JacobianMethod::kSensitivities;
    } else if (jacobian == "central_differences") {
      c.fit.jacobian = JacobianMethod::kCentralDifferences;
    } else {
      fit.fail("jacobian", "expected 'sensitivities' or 'central_differences', got '" + jacobian + "'");
    }
    fit.finish();

    const core::YamlMap initial = root.map("initial_states");
    for (const auto& [key, spec, unit] : {std::tuple{"speed_radps", &c.fit.initial_speed, "rad/s"},
                                          std::tuple{"torque_offset_nm", &c.fit.initial_torque_offset, "N m"}}) {
      const core::YamlMap p = initial.map(key);
      const std::string mode = p.string("mode");
      if (mode == "free") {
        spec->free = true;
      } else if (mode == "fixed") {
        spec->free = false;
      } else {
        p.fail("mode", "expected 'free' or 'fixed', got '" + mode + "'");
      }
      spec->log_scaled = false;
      spec->min = p.number("min", unit);
      spec->max = p.number("max", unit);
      if (!(spec->min <= 0.0)) p.fail("min", "expected <= 0 (the bounds hold the state at rest)");
      if (!(spec->max >= 0.0)) p.fail("max", "expected >= 0 (the bounds hold the state at rest)");
      p.finish();
    }
    initial.finish();

    const core::YamlMap params = root.map("parameters");
    for (int i = 0; i < kGreyParams; ++i) {
      const char* name = greyParamName(i);
      const core::YamlMap p = params.map(name);
      ParamSpec& s = c.fit.params[static_cast<std::size_t>(i)];
      const std::string scaling = p.string("scaling");
      if (scaling == "log") {
        s.log_scaled = true;
      } else if (scaling == "linear") {
        s.log_scaled = false;
      } else {
        p.fail("scaling", "expected 'log' or 'linear', got '" + scaling + "'");
      }
      const std::string mode = p.string("mode");
      if (mode == "free") {
        s.free = true;
      } else if (mode == "fixed") {
        s.free = false;
      } else {
        p.fail("mode", "expected 'free' or 'fixed', got '" + mode + "'");
      }
      s.min = p.number("min");
      s.max = p.number("max");
      if (!(s.min <= s.max)) p.fail("max", "expected >= min (" + std::to_string(s.min) + ")");
      if (s.log_scaled && !(s.min > 0.0)) p.fail("min", "a log-scaled parameter needs a positive lower bound");
      p.finish();
    }
    params.finish();

    const core::YamlMap val = root.map("validation");
    c.validation.min_fit_angle_percent = val.number("min_fit_angle_percent", "%");
    c.validation.min_fit_torque_percent = val.number("min_fit_torque_percent", "%");
    c.validation.max_lag = val.integer("max_lag");
    if (c.validation.max_lag < 1) val.fail("max_lag", "expected >= 1");
    for (const auto& [key, value] :
         {std::pair{"whiteness_max_outside_fraction", &c.validation.whiteness_max_outside_fraction},
          std::pair{"independence_max_outside_fraction", &c.validation.independence_max_outside_fraction}}) {
      *value = val.number(key);
      if (!(*value >= 0.0 && *value <= 1.0)) val.fail(key, "expected 0..1");
    }
    const core::YamlMap pred = val.map("prediction");
    PredictorNoise& noise = c.validation.prediction;
    noise.angle_rad = pred.number("angle_noise_rad", "rad");
    noise.torque_nm = pred.number("torque_noise_nm", "N m");
    noise.torque_cell_nm = pred.number("torque_cell_noise_nm", "N m");
    if (!(noise.torque_cell_nm >= 0.0)) pred.fail("torque_cell_noise_nm", "expected a standard deviation >= 0");
    noise.process_torque_nm = pred.number("process_torque_nm", "N m per sample");
    noise.process_speed_radps = pred.number("process_speed_radps", "rad/s per sample");
    for (const auto& [key, value] :
         {std::pair{"angle_noise_rad", noise.angle_rad}, std::pair{"torque_noise_nm", noise.torque_nm},
          std::pair{"process_torque_nm", noise.process_torque_nm},
          std::pair{"process_speed_radps", noise.process_speed_radps}}) {
      if (!(value > 0.0)) pred.fail(key, "expected a positive standard deviation");
    }
    pred.finish();
    val.finish();
    root.finish();
    return c;
  });
}

IdentificationConfig loadIdentificationConfig(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw core::ConfigError(file, "", "cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  return parseIdentificationConfig(text.str(), file);
}

std::filesystem::path defaultIdentificationConfigPath() {
  return core::defaultConfigPath("identification.yaml");
}

}  // namespace fullarm::identification
