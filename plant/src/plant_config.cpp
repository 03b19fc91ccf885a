#include "fullarm/plant/plant_config.hpp"

#include <cstdlib>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <vector>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::plant {
namespace {

constexpr int kSchemaVersion = 1;

JointParams readJoint(const core::YamlMap& m, const arm::ArmModel& model, const JointParams& shared, int& model_index) {
  JointParams p = shared;
  p.name = m.string("name");
  model_index = model.jointIndex(p.name);
  if (model_index < 0) m.fail("name", "unknown joint name '" + p.name + "': not a joint of arm model " + model.name);
  const arm::Joint& j = model.joints[static_cast<std::size_t>(model_index)];
  p.min_rad = j.limits.min_rad;
  p.max_rad = j.limits.max_rad;
  p.potentiometer = j.potentiometer;
  p.torque_sensor = j.torque_sensor;

  const std::string mode = m.string("input_mode");
  if (mode == "valve_voltage") {
    p.input_mode = InputMode::kValveVoltage;
  } else if (mode == "torque_loop") {
    p.input_mode = InputMode::kTorqueLoop;
  } else {
    m.fail("input_mode", "'" + mode + "' is not an input mode: expected valve_voltage or torque_loop");
  }

  const core::YamlMap v = m.map("valve");
  p.valve.natural_frequency_hz = v.number("natural_frequency_hz", "Hz");
  p.valve.damping_ratio = v.number("damping_ratio");
  p.valve.amplifier_gain_per_v = v.number("amplifier_gain_per_v", "normalised opening per volt");
  p.valve.spool_stroke_m = v.number("spool_stroke_m", "metres");
  p.valve.rated_flow_m3ps = v.number("rated_flow_m3ps", "m^3/s");
  p.valve.rated_pressure_drop_pa = v.number("rated_pressure_drop_pa", "Pa");
  p.valve.lap_pa_m = v.number("lap_pa_m", "metres");
  p.valve.lap_pb_m = v.number("lap_pb_m", "metres");
  p.valve.lap_at_m = v.number("lap_at_m", "metres");
  p.valve.lap_bt_m = v.number("lap_bt_m", "metres");
  p.valve.edge_rounding_m = v.number("edge_rounding_m", "metres");
  p.valve.linear_region_pa = v.number("linear_region_pa", "Pa");
  v.finish();

  const core::YamlMap a = m.map("actuator");
  const std::string type = a.string("type");
  p.actuator.inertia_kgm2 = a.number("inertia_kgm2", "kg m^2");
  if (type == "rotary_vane") {
    if (j.actuator.type != arm::ActuatorGeometry::Type::kRotary) {
      a.fail("type", "rotary_vane, but the arm model gives joint " + p.name + " a linear actuator: expected cylinder");
    }
    p.actuator.kind = ActuatorKind::kRotaryVane;
    p.actuator.displacement_m3_per_rad = a.number("displacement_m3_per_rad", "m^3/rad");
  } else if (type == "cylinder") {
    if (j.actuator.type != arm::ActuatorGeometry::Type::kLinear) {
      a.fail("type", "cylinder, but the arm model gives joint " + p.name + " a rotary actuator: expected rotary_vane");
    }
    p.actuator.kind = ActuatorKind::kCylinder;
    p.actuator.piston_area_a_m2 = a.number("piston_area_a_m2", "m^2");
    p.actuator.piston_area_b_m2 = a.number("piston_area_b_m2", "m^2");
    p.actuator.lever = j.actuator;
  } else {
    a.fail("type", "'" + type + "' is not an actuator type: expected rotary_vane or cylinder");
  }
  a.finish();

  const core::YamlMap c = m.map("chambers");
  p.chambers.dead_volume_a_m3 = c.number("dead_volume_a_m3", "m^3");
  p.chambers.dead_volume_b_m3 = c.number("dead_volume_b_m3", "m^3");
  p.chambers.internal_leakage_m3ps_per_pa = c.number("internal_leakage_m3ps_per_pa", "m^3/s/Pa");
  p.chambers.external_leakage_m3ps_per_pa = c.number("external_leakage_m3ps_per_pa", "m^3/s/Pa");
  p.chambers.check_valve_conductance_m3ps_per_pa = c.number("check_valve_conductance_m3ps_per_pa", "m^3/s/Pa");
  c.finish();

  const core::YamlMap f = m.map("friction");
  p.friction.coulomb_nm = f.number("coulomb_nm", "N m");
  p.friction.static_nm = f.number("static_nm", "N m");
  p.friction.stribeck_velocity_radps = f.number("stribeck_velocity_radps", "rad/s");
  p.friction.viscous_nms_per_rad = f.number("viscous_nms_per_rad", "N m s/rad");
  p.friction.smoothing_velocity_radps = f.number("smoothing_velocity_radps", "rad/s");
  f.finish();

  const core::YamlMap h = m.map("hard_stop");
  p.hard_stop.stiffness_nm_per_rad = h.number("stiffness_nm_per_rad", "N m/rad");
  p.hard_stop.damping_s_per_rad = h.number("damping_s_per_rad", "s/rad");
  h.finish();

  const core::YamlMap t = m.map("torque_loop");
  p.torque_loop.gain_v_per_nm = t.number("gain_v_per_nm", "V per N m");
  t.finish();

  const core::YamlMap s = m.map("sensors");
  p.sensor_noise.angle_noise_rad = s.number("angle_noise_rad", "rad");
  p.sensor_noise.torque_noise_nm = s.number("torque_noise_nm", "N m");
  p.sensor_noise.torque_bias_nm = s.number("torque_bias_nm", "N m");
  p.sensor_noise.torque_filter_hz = s.number("torque_filter_hz", "Hz");
  if (const auto full_scale = s.optionalNumber("pressure_full_scale_pa", "Pa")) {
    p.sensor_noise.pressure_full_scale_pa = *full_scale;
    p.sensor_noise.pressure_bits = s.integer("pressure_bits");
    p.sensor_noise.pressure_noise_pa = s.number("pressure_noise_pa", "Pa");
  }
  s.finish();
  m.finish();
  return p;
}

PlantConfig build(const core::YamlMap& root, const std::filesystem::path& source, const arm::ArmModel& model) {
  PlantConfig config;
  config.source = source;
  if (root.integer("schema_version") != kSchemaVersion) root.fail("schema_version", "expected 1");
  JointParams shared;
  const core::YamlMap supply = root.map("supply");
  shared.supply_pressure_pa = supply.number("supply_pressure_pa", "Pa");
  shared.return_pressure_pa = supply.number("return_pressure_pa", "Pa");
  supply.finish();
  const core::YamlMap fluid = root.map("fluid");
  shared.fluid.oil_bulk_modulus_pa = fluid.number("oil_bulk_modulus_pa", "Pa");
  shared.fluid.air_fraction = fluid.number("air_fraction", "volume fraction at atmospheric pressure");
  shared.fluid.polytropic_index = fluid.number("polytropic_index");
  shared.fluid.atmospheric_pressure_pa = fluid.number("atmospheric_pressure_pa", "Pa");
  fluid.finish();
  auto check = [](const core::YamlMap& m, const char* key, double v, double lo, double hi) {
    if (!(v >= lo && v <= hi)) {
      m.fail(key, "value " + std::to_string(v) + " is out of range: expected [" + std::to_string(lo) + ", " +
                      std::to_string(hi) + "]");
    }
  };
  check(supply, "supply_pressure_pa", shared.supply_pressure_pa, 1e5, 1e8);
  check(supply, "return_pressure_pa", shared.return_pressure_pa, 0.0, shared.supply_pressure_pa * 0.5);
  check(fluid, "oil_bulk_modulus_pa", shared.fluid.oil_bulk_modulus_pa, 1e7, 1e11);
  check(fluid, "air_fraction", shared.fluid.air_fraction, 0.0, 0.2);
  check(fluid, "polytropic_index", shared.fluid.polytropic_index, 1.0, 1.67);
  check(fluid, "atmospheric_pressure_pa", shared.fluid.atmospheric_pressure_pa, 5e4, 2e5);

  const core::YamlMap solver = root.map("solver");
  SolverOptions& o = config.solver;
  o.rtol = solver.number("rtol");
  o.atol_spool = solver.number("atol_spool");
  o.atol_spool_rate_per_s = solver.number("atol_spool_rate_per_s", "1/s");
  o.atol_pressure_pa = solver.number("atol_pressure_pa", "Pa");
  o.atol_angle_rad = solver.number("atol_angle_rad", "rad");
  o.atol_velocity_radps = solver.number("atol_velocity_radps", "rad/s");
  o.max_steps_per_period = solver.integer("max_steps_per_period");
  o.reinit_command_jump = solver.number("reinit_command_jump", "fraction of full scale");
  const std::string jac = solver.string("jacobian");
  if (jac == "analytic") {
    o.jacobian = JacobianKind::kAnalytic;
  } else if (jac == "finite_difference") {
    o.jacobian = JacobianKind::kFiniteDifference;
  } else {
    solver.fail("jacobian", "'" + jac + "': expected analytic or finite_difference");
  }
  const std::string integrator = solver.optionalString("integrator").value_or("cvodes");
  if (integrator == "cvodes") {
    o.integrator = IntegratorKind::kCvodes;
  } else if (integrator == "rodas3") {
    o.integrator = IntegratorKind::kRodas3;
  } else if (integrator == "rodas4") {
    o.integrator = IntegratorKind::kRodas4;
  } else if (integrator == "ros34pw2") {
    o.integrator = IntegratorKind::kRos34pw2;
  } else {
    solver.fail("integrator", "'" + integrator + "': expected cvodes, rodas3, rodas4 or ros34pw2");
  }
  for (const auto& [key, value] :
       {std::pair{"rtol", o.rtol}, std::pair{"atol_spool", o.atol_spool},
        std::pair{"atol_spool_rate_per_s", o.atol_spool_rate_per_s}, std::pair{"atol_pressure_pa", o.atol_pressure_pa},
        std::pair{"atol_angle_rad", o.atol_angle_rad}, std::pair{"atol_velocity_radps", o.atol_velocity_radps}}) {
    if (!(value > 0.0 && value < 1e9)) solver.fail(key, "expected a positive tolerance");
  }
  if (!(o.rtol < 1e-2)) solver.fail("rtol", "expected a relative tolerance below 1e-2");
  if (o.max_steps_per_period < 10) solver.fail("max_steps_per_period", "expected at least 10");
  if (!(o.reinit_command_jump > 0.0)) solver.fail("reinit_command_jump", "expected a positive fraction");
  solver.finish();

  const core::YamlMap user = root.map("user_arm");
  UserArmParams& u = config.user_arm;
  const std::string enabled = user.string("enabled");
  if (enabled != "true" && enabled != "false") user.fail("enabled", "'" + enabled + "': expected true or false");
  u.enabled = enabled == "true";
  const std::string link = user.string("link");
  u.link = model.jointIndex(link);
  if (u.link < 0) user.fail("link", "unknown link (joint) name '" + link + "'");
  u.point_L = user.vector3("point_m", "metres, link frame");
  u.mass_kg = user.number("mass_kg", "kg");
  u.stiffness_n_per_m = user.number("stiffness_n_per_m", "N/m");
  u.damping_ns_per_m = user.number("damping_ns_per_m", "N s/m");
  if (!(u.mass_kg >= 0.0)) user.fail("mass_kg", "expected >= 0");
  if (!(u.stiffness_n_per_m >= 0.0)) user.fail("stiffness_n_per_m", "expected >= 0");
  if (!(u.damping_ns_per_m >= 0.0)) user.fail("damping_ns_per_m", "expected >= 0");
  user.finish();

  const int seed = root.integer("noise_seed");
  if (seed < 0) root.fail("noise_seed", "expected a seed >= 0");
  config.seed = static_cast<std::uint64_t>(seed);

  const core::YamlList joints = root.list("joints");
  std::vector<int> indices;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const core::YamlMap jm = joints.map(i);
    int index = -1;
    JointParams p = readJoint(jm, model, shared, index);
    for (int seen : indices) {
      if (seen == index) jm.fail("name", "joint '" + p.name + "' is listed twice");
    }
    if (model.joints[static_cast<std::size_t>(index)].is_hand)
      jm.fail("name", "hand joint '" + p.name + "' has no hydraulic model");
    validateJointParams(p, source.string(), jm.path());
    indices.push_back(index);
    config.joints.push_back(std::move(p));
  }
  if (config.joints.size() != static_cast<std::size_t>(model.numArmJoints())) {
    root.fail("joints", "expected one entry per arm joint (" + std::to_string(model.numArmJoints()) + "), got " +
                            std::to_string(config.joints.size()));
  }
  root.finish();
  return config;
}

}  // namespace

PlantConfig parsePlantConfig(std::string_view yaml_text, const std::filesystem::path& source,
                             const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, source);
  return core::withKeyPathLines(root, [&] { return build(root, source, model); });
}

PlantConfig loadPlantConfig(const std::filesystem::path& file, const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::load(file);
  return core::withKeyPathLines(root, [&] { return build(root, file, model); });
}

std::filesystem::path defaultPlantConfigPath() {
  return core::defaultConfigPath("dts_plant.yaml");
}

int findPlantJoint(const PlantConfig& config, std::string_view name) {
  std::vector<std::string_view> names;
  names.reserve(config.joints.size());
  for (const JointParams& p : config.joints) names.emplace_back(p.name);
  return arm::findJointByName(names, name, config.source);
}

}  // namespace fullarm::plant

namespace fullarm::plant {
namespace {

std::string num(double v) {
  std::ostringstream s;
  s << std::setprecision(17) << v;
  return s.str();
}

const char* integratorName(IntegratorKind k) {
  switch (k) {
    case IntegratorKind::kCvodes:
      return "cvodes";
    case IntegratorKind::kRodas3:
      return "rodas3";
    case IntegratorKind::kRodas4:
      return "rodas4";
    case IntegratorKind::kRos34pw2:
      return "ros34pw2";
  }
  return "cvodes";
}

}  // namespace

std::string formatPlantConfigYaml(const PlantConfig& config, const arm::ArmModel& model,
                                  const std::vector<std::string>& header) {
  if (config.joints.empty()) throw std::invalid_argument("formatPlantConfigYaml: the plant has no joints");
  const JointParams& first = config.joints.front();
  for (const JointParams& p : config.joints) {
    if (p.supply_pressure_pa != first.supply_pressure_pa || p.return_pressure_pa != first.return_pressure_pa ||
        p.fluid.oil_bulk_modulus_pa != first.fluid.oil_bulk_modulus_pa ||
        p.fluid.air_fraction != first.fluid.air_fraction || p.fluid.polytropic_index != first.fluid.polytropic_index ||
        p.fluid.atmospheric_pressure_pa != first.fluid.atmospheric_pressure_pa) {
      throw std::invalid_argument("formatPlantConfigYaml: joint " + p.name + " has another supply or fluid than " +
                                  first.name + " (the file holds one of each)");
    }
  }
  const UserArmParams& u = config.user_arm;
  if (u.link < 0 || u.link >= static_cast<int>(model.joints.size())) {
    throw std::invalid_argument("formatPlantConfigYaml: the user arm's link " + std::to_string(u.link) +
                                " is not a joint of arm model " + model.name);
  }
  std::ostringstream o;
  for (const std::string& line : header) o << "# " << line << "\n";
  const SolverOptions& s = config.solver;
  o << "schema_version: " << kSchemaVersion << "\n\n"
    << "supply:\n"
    << "  supply_pressure_pa: " << num(first.supply_pressure_pa) << "\n"
    << "  return_pressure_pa: " << num(first.return_pressure_pa) << "\n\n"
    << "fluid:\n"
    << "  oil_bulk_modulus_pa: " << num(first.fluid.oil_bulk_modulus_pa) << "\n"
    << "  air_fraction: " << num(first.fluid.air_fraction) << "\n"
    << "  polytropic_index: " << num(first.fluid.polytropic_index) << "\n"
    << "  atmospheric_pressure_pa: " << num(first.fluid.atmospheric_pressure_pa) << "\n\n"
    << "solver:\n"
    << "  rtol: " << num(s.rtol) << "\n"
    << "  atol_spool: " << num(s.atol_spool) << "\n"
    << "  atol_spool_rate_per_s: " << num(s.atol_spool_rate_per_s) << "\n"
    << "  atol_pressure_pa: " << num(s.atol_pressure_pa) << "\n"
    << "  atol_angle_rad: " << num(s.atol_angle_rad) << "\n"
    << "  atol_velocity_radps: " << num(s.atol_velocity_radps) << "\n"
    << "  max_steps_per_period: " << s.max_steps_per_period << "\n"
    << "  reinit_command_jump: " << num(s.reinit_command_jump) << "\n"
    << "  jacobian: " << (s.jacobian == JacobianKind::kAnalytic ? "analytic" : "finite_difference") << "\n"
    << "  integrator: " << integratorName(s.integrator) << "\n\n"
    << "user_arm:\n"
    << "  enabled: " << (u.enabled ? "true" : "false") << "\n"
    << "  link: " << model.joints[static_cast<std::size_t>(u.link)].name << "\n"
    << "  point_m: [" << num(u.point_L.x()) << ", " << num(u.point_L.y()) << ", " << num(u.point_L.z()) << "]\n"
    << "  mass_kg: " << num(u.mass_kg) << "\n"
    << "  stiffness_n_per_m: " << num(u.stiffness_n_per_m) << "\n"
    << "  damping_ns_per_m: " << num(u.damping_ns_per_m) << "\n\n"
    << "noise_seed: " << config.seed << "\n\n"
    << "joints:\n";
  for (const JointParams& p : config.joints) {
    const ValveParams& v = p.valve;
    const ActuatorParams& a = p.actuator;
    const ChamberParams& c = p.chambers;
    const FrictionParams& f = p.friction;
    const SensorNoiseParams& n = p.sensor_noise;
    o << "  - name: " << p.name << "\n"
      << "    input_mode: " << (p.input_mode == InputMode::kValveVoltage ? "valve_voltage" : "torque_loop") << "\n"
      << "    valve: {natural_frequency_hz: " << num(v.natural_frequency_hz)
      << ", damping_ratio: " << num(v.damping_ratio) << ", amplifier_gain_per_v: " << num(v.amplifier_gain_per_v)
      << ", spool_stroke_m: " << num(v.spool_stroke_m) << ", rated_flow_m3ps: " << num(v.rated_flow_m3ps)
      << ", rated_pressure_drop_pa: " << num(v.rated_pressure_drop_pa) << ", lap_pa_m: " << num(v.lap_pa_m)
      << ", lap_pb_m: " << num(v.lap_pb_m) << ", lap_at_m: " << num(v.lap_at_m) << ", lap_bt_m: " << num(v.lap_bt_m)
      << ", edge_rounding_m: " << num(v.edge_rounding_m) << ", linear_region_pa: " << num(v.linear_region_pa) << "}\n";
    if (a.kind == ActuatorKind::kCylinder) {
      o << "    actuator: {type: cylinder, piston_area_a_m2: " << num(a.piston_area_a_m2)
        << ", piston_area_b_m2: " << num(a.piston_area_b_m2) << ", inertia_kgm2: " << num(a.inertia_kgm2) << "}\n";
    } else if (a.kind == ActuatorKind::kRotaryVane) {
      o << "    actuator: {type: rotary_vane, displacement_m3_per_rad: " << num(a.displacement_m3_per_rad)
        << ", inertia_kgm2: " << num(a.inertia_kgm2) << "}\n";
    } else {
      throw std::invalid_argument("formatPlantConfigYaml: joint " + p.name +
                                  " has an ideal torque actuator, which the plant file cannot hold");
    }
    o << "    chambers: {dead_volume_a_m3: " << num(c.dead_volume_a_m3)
      << ", dead_volume_b_m3: " << num(c.dead_volume_b_m3)
      << ", internal_leakage_m3ps_per_pa: " << num(c.internal_leakage_m3ps_per_pa)
      << ", external_leakage_m3ps_per_pa: " << num(c.external_leakage_m3ps_per_pa)
      << ", check_valve_conductance_m3ps_per_pa: " << num(c.check_valve_conductance_m3ps_per_pa) << "}\n"
      << "    friction: {coulomb_nm: " << num(f.coulomb_nm) << ", static_nm: " << num(f.static_nm)
      << ", stribeck_velocity_radps: " << num(f.stribeck_velocity_radps)
      << ", viscous_nms_per_rad: " << num(f.viscous_nms_per_rad)
      << ", smoothing_velocity_radps: " << num(f.smoothing_velocity_radps) << "}\n"
      << "    hard_stop: {stiffness_nm_per_rad: " << num(p.hard_stop.stiffness_nm_per_rad)
      << ", damping_s_per_rad: " << num(p.hard_stop.damping_s_per_rad) << "}\n"
      << "    torque_loop: {gain_v_per_nm: " << num(p.torque_loop.gain_v_per_nm) << "}\n"
      << "    sensors: {angle_noise_rad: " << num(n.angle_noise_rad) << ", torque_noise_nm: " << num(n.torque_noise_nm)
      << ", torque_bias_nm: " << num(n.torque_bias_nm) << ", torque_filter_hz: " << num(n.torque_filter_hz);
    if (n.pressure_full_scale_pa > 0.0) {
      o << ", pressure_full_scale_pa: " << num(n.pressure_full_scale_pa) << ", pressure_bits: " << n.pressure_bits
        << ", pressure_noise_pa: " << num(n.pressure_noise_pa);
    }
    o << "}\n";
  }
  return o.str();
}

}  // namespace fullarm::plant
