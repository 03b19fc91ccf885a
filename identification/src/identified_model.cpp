#include "fullarm/identification/identified_model.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "fullarm/core/config_error.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::identification {
namespace {

constexpr int kSchemaVersion = 1;

std::string exact(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", v);
  return buf;
}

// The groups that are positive by construction (log-scaled in the fit).
bool positiveGroup(int i) {
  return i == kFlowGain || i == kStiffness || i == kLeakage || i == kInertia || i == kViscous || i == kCoulomb;
}

}  // namespace

std::string formatIdentifiedModelYaml(const IdentifiedModel& id) {
  std::ostringstream s;
  s << "# Identified reduced model of one joint (docs/identification.md): each parameter group with\n"
       "# its standard error (0: held fixed in the fit).\n";
  s << "schema_version: " << kSchemaVersion << "\n";
  s << "joint: " << id.joint << "\n";
  s << "delay_samples: " << id.model.delay_samples << "\n";
  s << "coulomb_smoothing_radps: " << exact(id.model.coulomb_smoothing_radps) << "\n";
  s << "spool_hz: " << exact(id.model.spool_hz) << "\n";
  s << "spool_damping: " << exact(id.model.spool_damping) << "\n";
  s << "torque_filter_hz: " << exact(id.model.torque_filter_hz) << "\n";
  s << "stribeck_velocity_radps: " << exact(id.model.stribeck_velocity_radps) << "\n";
  s << "stall_torque_nm: " << exact(id.model.stall_torque_nm) << "\n";
  s << "underlap_v: " << exact(id.model.underlap_v) << "\n";
  s << "edge_rounding_v: " << exact(id.model.edge_rounding_v) << "\n";
  s << "load_gradient_nm_per_rad: " << exact(id.model.load_gradient_nm_per_rad) << "\n";
  s << "parameters:\n";
  for (int i = 0; i < kGreyParams; ++i) {
    const auto k = static_cast<std::size_t>(i);
    s << "  " << greyParamName(i) << ": {value: " << exact(id.model.value[k])
      << ", standard_error: " << exact(id.standard_error[k]) << "}\n";
  }
  return s.str();
}

IdentifiedModel parseIdentifiedModelYaml(std::string_view yaml_text, const std::filesystem::path& source) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, source);
  return core::withKeyPathLines(root, [&] {
    IdentifiedModel id;
    if (root.integer("schema_version") != kSchemaVersion) root.fail("schema_version", "expected 1");
    id.joint = root.string("joint");
    if (id.joint.empty()) root.fail("joint", "expected a joint name");
    id.model.delay_samples = root.integer("delay_samples");
    if (id.model.delay_samples < 0) root.fail("delay_samples", "expected >= 0");
    id.model.coulomb_smoothing_radps = root.number("coulomb_smoothing_radps", "rad/s");
    if (!(id.model.coulomb_smoothing_radps > 0.0)) root.fail("coulomb_smoothing_radps", "expected > 0");
    id.model.spool_hz = root.number("spool_hz", "Hz");
    if (id.model.spool_hz < 0.0) root.fail("spool_hz", "expected >= 0 (0: no spool)");
    id.model.spool_damping = root.number("spool_damping");
    if (!(id.model.spool_damping > 0.0)) root.fail("spool_damping", "expected > 0");
    id.model.torque_filter_hz = root.number("torque_filter_hz", "Hz");
    if (id.model.torque_filter_hz < 0.0) root.fail("torque_filter_hz", "expected >= 0 (0: no filter)");
    id.model.stribeck_velocity_radps = root.number("stribeck_velocity_radps", "rad/s");
    if (!(id.model.stribeck_velocity_radps > 0.0)) root.fail("stribeck_velocity_radps", "expected > 0");
    id.model.stall_torque_nm = root.number("stall_torque_nm", "N m");
    if (id.model.stall_torque_nm < 0.0) root.fail("stall_torque_nm", "expected >= 0 (0: load-independent flow)");
    id.model.underlap_v = root.number("underlap_v", "V");
    if (id.model.underlap_v < 0.0) root.fail("underlap_v", "expected >= 0");
    id.model.edge_rounding_v = root.number("edge_rounding_v", "V");
    if (id.model.edge_rounding_v < 0.0) root.fail("edge_rounding_v", "expected >= 0");
    id.model.load_gradient_nm_per_rad = root.number("load_gradient_nm_per_rad", "N m/rad");
    const core::YamlMap params = root.map("parameters");
    for (int i = 0; i < kGreyParams; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const core::YamlMap p = params.map(greyParamName(i));
      id.model.value[k] = p.number("value");
      if (positiveGroup(i) && !(id.model.value[k] > 0.0)) p.fail("value", "expected > 0");
      if (i == kStribeck && id.model.value[k] < 0.0) p.fail("value", "expected >= 0");
      id.standard_error[k] = p.number("standard_error");
      if (id.standard_error[k] < 0.0) p.fail("standard_error", "expected >= 0");
      p.finish();
    }
    params.finish();
    root.finish();
    return id;
  });
}

IdentifiedModel loadIdentifiedModel(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw core::ConfigError(file, "", "cannot be read");
  std::ostringstream text;
  text << in.rdbuf();
  return parseIdentifiedModelYaml(text.str(), file);
}

}  // namespace fullarm::identification
