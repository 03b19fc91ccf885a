#include "fullarm/controllers/gains.hpp"

#include <cmath>
#include <iomanip>
#include <limits>
#include <sstream>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::controllers {
namespace {

constexpr int kSchemaVersion = 1;
constexpr double kMinPeriodS = 1.0e-5;
constexpr double kMaxPeriodS = 0.1;

std::string show(double v) {
  std::ostringstream os;
  os << std::setprecision(6) << v;
  return os.str();
}

std::string joinKey(const std::string& prefix, const std::string& key) {
  return prefix.empty() ? key : prefix + "." + key;
}

bool readBool(const core::YamlMap& m, std::string_view key) {
  const std::string v = m.string(key);
  if (v == "true") return true;
  if (v == "false") return false;
  m.fail(key, "'" + v + "': expected true or false");
}

JointGains readJoint(const core::YamlMap& m) {
  JointGains g;
  g.name = m.string("name");

  const core::YamlMap imp = m.map("impedance");
  g.impedance.inertia_kgm2 = imp.number("inertia_kgm2", "kg m^2");
  g.impedance.damping_nms_per_rad = imp.number("damping_nms_per_rad", "N m s/rad");
  g.impedance.stiffness_nm_per_rad = imp.number("stiffness_nm_per_rad", "N m/rad");
  imp.finish();

  const core::YamlMap sm = m.map("sliding_mode");
  g.sliding_mode.lambda_per_s = sm.number("lambda_per_s", "1/s");
  g.sliding_mode.valve_bound_v = sm.number("valve_bound_v", "V");
  g.sliding_mode.boundary_layer_radps = sm.number("boundary_layer_radps", "rad/s");
  sm.finish();

  const core::YamlMap pid = m.map("torque_pid");
  g.torque_pid.kp_v_per_nm = pid.number("kp_v_per_nm", "V per N m");
  g.torque_pid.ki_v_per_nms = pid.number("ki_v_per_nms", "V per N m s");
  g.torque_pid.kd_vs_per_nm = pid.number("kd_vs_per_nm", "V s per N m");
  g.torque_pid.integral_limit_v = pid.number("integral_limit_v", "V");
  pid.finish();

  const core::YamlMap po = m.map("passivity");
  g.passivity.enabled = readBool(po, "enabled");
  g.passivity.max_damping_nms_per_rad = po.number("max_damping_nms_per_rad", "N m s/rad");
  g.passivity.velocity_threshold_radps = po.number("velocity_threshold_radps", "rad/s");
  po.finish();

  g.torque_filter_hz = m.number("torque_filter_hz", "Hz");
  g.error_rate_filter_hz = m.number("error_rate_filter_hz", "Hz");
  g.valve_limit_v = m.number("valve_limit_v", "V");
  m.finish();
  return g;
}

GainsConfig build(const core::YamlMap& root, const std::filesystem::path& source, const arm::ArmModel& model) {
  GainsConfig config;
  config.source = source;
  if (root.integer("schema_version") != kSchemaVersion) root.fail("schema_version", "expected 1");
  const std::string kind = root.string("controller");
  if (kind == "admittance") {
    config.controller = ControllerKind::kAdmittance;
  } else if (kind == "torque_pid") {
    config.controller = ControllerKind::kTorquePid;
  } else {
    root.fail("controller", "'" + kind + "' is not a controller: expected admittance or torque_pid");
  }
  config.control_period_s = root.number("control_period_s", "s");
  if (!(config.control_period_s >= kMinPeriodS && config.control_period_s <= kMaxPeriodS)) {
    root.fail("control_period_s", "value " + show(config.control_period_s) + " is out of range: expected [" +
                                      show(kMinPeriodS) + ", " + show(kMaxPeriodS) + "] s");
  }

  const core::YamlList joints = root.list("joints");
  if (joints.size() == 0) root.fail("joints", "expected at least one joint");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const core::YamlMap jm = joints.map(i);
    JointGains g = readJoint(jm);
    const int index = model.jointIndex(g.name);
    if (index < 0) {
      std::string known;
      for (int k = 0; k < model.numJoints(); ++k) {
        if (model.joints[static_cast<std::size_t>(k)].is_hand) continue;
        known += (known.empty() ? "" : ", ") + model.joints[static_cast<std::size_t>(k)].name;
      }
      jm.fail("name", "unknown joint '" + g.name + "': not a joint of arm model " + model.name + " (expected one of " +
                          known + ")");
    }
    if (model.joints[static_cast<std::size_t>(index)].is_hand) {
      jm.fail("name", "hand joint '" + g.name + "' has no hydraulic actuator to control");
    }
    for (const JointGains& seen : config.joints) {
      if (seen.name == g.name) jm.fail("name", "joint '" + g.name + "' is listed twice");
    }
    validateJointGains(g, config.control_period_s, source.string(), jm.path());
    config.joints.push_back(std::move(g));
  }
  root.finish();
  return config;
}

}  // namespace

void validateJointGains(const JointGains& g, double control_period_s, const std::string& file,
                        const std::string& key_path) {
  auto fail = [&](const std::string& key, const std::string& message) {
    throw core::ConfigError(file, joinKey(key_path, key), message);
  };
  auto positive = [&](const std::string& key, double v, const char* what) {
    if (!(std::isfinite(v) && v > 0.0)) fail(key, "value " + show(v) + ": expected " + what + " > 0");
  };
  auto nonNegative = [&](const std::string& key, double v, const char* what) {
    if (!(std::isfinite(v) && v >= 0.0)) fail(key, "value " + show(v) + ": expected " + what + " >= 0");
  };
  if (!(std::isfinite(control_period_s) && control_period_s > 0.0)) {
    fail("control_period_s", "value " + show(control_period_s) + ": expected a period > 0");
  }
  if (g.name.empty()) fail("name", "expected a joint name");
  positive("impedance.inertia_kgm2", g.impedance.inertia_kgm2, "an impedance-model inertia J_m");
  nonNegative("impedance.damping_nms_per_rad", g.impedance.damping_nms_per_rad, "an impedance-model damping B_m");
  positive("impedance.stiffness_nm_per_rad", g.impedance.stiffness_nm_per_rad, "an impedance-model stiffness K_m");
  positive("sliding_mode.lambda_per_s", g.sliding_mode.lambda_per_s, "a sliding-surface slope lambda");
  positive("sliding_mode.valve_bound_v", g.sliding_mode.valve_bound_v, "a valve bound B_o");
  positive("sliding_mode.boundary_layer_radps", g.sliding_mode.boundary_layer_radps, "a boundary layer eps");
  nonNegative("torque_pid.kp_v_per_nm", g.torque_pid.kp_v_per_nm, "a proportional gain");
  nonNegative("torque_pid.ki_v_per_nms", g.torque_pid.ki_v_per_nms, "an integral gain");
  nonNegative("torque_pid.kd_vs_per_nm", g.torque_pid.kd_vs_per_nm, "a derivative gain");
  nonNegative("torque_pid.integral_limit_v", g.torque_pid.integral_limit_v, "an integral clamp");
  positive("passivity.max_damping_nms_per_rad", g.passivity.max_damping_nms_per_rad, "a damping cap");
  nonNegative("passivity.velocity_threshold_radps", g.passivity.velocity_threshold_radps, "a velocity threshold");
  const double nyquist_hz = 0.5 / control_period_s;
  for (const auto& [key, hz] :
       {std::pair{"torque_filter_hz", g.torque_filter_hz}, std::pair{"error_rate_filter_hz", g.error_rate_filter_hz}}) {
    if (!(std::isfinite(hz) && hz >= 0.0 && hz < nyquist_hz)) {
      fail(key, "value " + show(hz) + ": expected a cutoff in [0, " + show(nyquist_hz) +
                    ") Hz (0 = no filter; below the Nyquist frequency of the control period)");
    }
  }
  positive("valve_limit_v", g.valve_limit_v, "a valve-command limit");
  if (g.sliding_mode.valve_bound_v > g.valve_limit_v) {
    fail("sliding_mode.valve_bound_v", "value " + show(g.sliding_mode.valve_bound_v) +
                                           ": expected B_o <= valve_limit_v (" + show(g.valve_limit_v) + " V)");
  }
}

GainsConfig parseGainsConfig(std::string_view yaml_text, const std::filesystem::path& source,
                             const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, source);
  return core::withKeyPathLines(root, [&] { return build(root, source, model); });
}

GainsConfig loadGainsConfig(const std::filesystem::path& file, const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::load(file);
  return core::withKeyPathLines(root, [&] { return build(root, file, model); });
}

std::string formatGainsYaml(const GainsConfig& config) {
  std::ostringstream os;
  os << std::setprecision(std::numeric_limits<double>::max_digits10);
  os << "# DTS joint controller gains (schema: docs/controllers.md)\n";
  os << "schema_version: " << kSchemaVersion << "\n";
  os << "controller: " << controllerKindName(config.controller) << "\n";
  os << "control_period_s: " << config.control_period_s << "\n";
  os << "joints:\n";
  for (const JointGains& g : config.joints) {
    os << "  - name: " << g.name << "\n";
    os << "    impedance: {inertia_kgm2: " << g.impedance.inertia_kgm2
       << ", damping_nms_per_rad: " << g.impedance.damping_nms_per_rad
       << ", stiffness_nm_per_rad: " << g.impedance.stiffness_nm_per_rad << "}\n";
    os << "    sliding_mode: {lambda_per_s: " << g.sliding_mode.lambda_per_s
       << ", valve_bound_v: " << g.sliding_mode.valve_bound_v
       << ", boundary_layer_radps: " << g.sliding_mode.boundary_layer_radps << "}\n";
    os << "    torque_pid: {kp_v_per_nm: " << g.torque_pid.kp_v_per_nm
       << ", ki_v_per_nms: " << g.torque_pid.ki_v_per_nms << ", kd_vs_per_nm: " << g.torque_pid.kd_vs_per_nm
       << ", integral_limit_v: " << g.torque_pid.integral_limit_v << "}\n";
    os << "    passivity: {enabled: " << (g.passivity.enabled ? "true" : "false")
       << ", max_damping_nms_per_rad: " << g.passivity.max_damping_nms_per_rad
       << ", velocity_threshold_radps: " << g.passivity.velocity_threshold_radps << "}\n";
    os << "    torque_filter_hz: " << g.torque_filter_hz << "\n";
    os << "    error_rate_filter_hz: " << g.error_rate_filter_hz << "\n";
    os << "    valve_limit_v: " << g.valve_limit_v << "\n";
  }
  return os.str();
}

std::filesystem::path defaultGainsConfigPath() {
  return core::defaultConfigPath("dts_gains.yaml");
}

std::filesystem::path defaultTuneStartGainsPath() {
  return core::defaultConfigPath("dts_tune_start.yaml");
}

int findGainsJoint(const GainsConfig& config, std::string_view name) {
  std::vector<std::string_view> names;
  names.reserve(config.joints.size());
  for (const JointGains& g : config.joints) names.emplace_back(g.name);
  return arm::findJointByName(names, name, config.source);
}

std::string_view controllerKindName(ControllerKind kind) noexcept {
  return kind == ControllerKind::kTorquePid ? "torque_pid" : "admittance";
}

}  // namespace fullarm::controllers
