#include "fullarm/arm/arm_yaml.hpp"

#include <cmath>
#include <cstdlib>
#include <numbers>

#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::arm {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;
constexpr int kSchemaVersion = 1;

Eigen::Isometry3d readPose(const core::YamlMap& m) {
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.translation() = m.vector3("translation_m", "metres");
  const Eigen::Vector3d rpy = m.vector3("rpy_deg", "roll, pitch, yaw in degrees") * kDegToRad;
  X.linear() = rotationFromRpy(rpy.x(), rpy.y(), rpy.z());
  m.finish();
  return X;
}

LinkGeometry readGeometry(const core::YamlMap& m, const std::filesystem::path& file) {
  LinkGeometry g;
  const std::string type = m.string("type");
  if (type == "none") {
    g.type = LinkGeometry::Type::kNone;
  } else if (type == "capsule") {
    g.type = LinkGeometry::Type::kCapsule;
    g.radius_m = m.number("radius_m", "metres");
    g.from_m = m.vector3("from_m", "metres, link frame");
    g.to_m = m.vector3("to_m", "metres, link frame");
  } else if (type == "mesh") {
    g.type = LinkGeometry::Type::kMesh;
    std::filesystem::path mesh = m.string("file");
    if (mesh.is_relative()) mesh = file.parent_path() / mesh;
    if (!std::filesystem::is_regular_file(mesh)) m.fail("file", "mesh file not found: " + mesh.string());
    g.mesh_file = mesh;
    g.mesh_scale = m.number("scale", "mesh units to metres");
    g.X_LM = readPose(m.map("pose"));
  } else {
    m.fail("type", "expected one of none, capsule, mesh; got '" + type + "'");
  }
  m.finish();
  return g;
}

LinkInertial readInertial(const core::YamlMap& link) {
  LinkInertial in;
  in.mass_kg = link.number("mass_kg", "kg");
  in.com_m = link.vector3("com_m", "metres, link frame");
  const core::YamlMap I = link.map("inertia_kgm2");
  const double xx = I.number("xx", "kg m^2");
  const double yy = I.number("yy", "kg m^2");
  const double zz = I.number("zz", "kg m^2");
  const double xy = I.number("xy", "kg m^2");
  const double xz = I.number("xz", "kg m^2");
  const double yz = I.number("yz", "kg m^2");
  I.finish();
  // Matrix entries: the off-diagonal values are the entries of the inertia matrix
  // (I_xy = -integral x y dm), not the positive products of inertia.
  in.inertia_com_kgm2 << xx, xy, xz, xy, yy, yz, xz, yz, zz;
  return in;
}

ActuatorGeometry readActuator(const core::YamlMap& m) {
  ActuatorGeometry act;
  const std::string type = m.string("type");
  if (type == "rotary") {
    act.type = ActuatorGeometry::Type::kRotary;
  } else if (type == "linear") {
    act.type = ActuatorGeometry::Type::kLinear;
    act.moment_arm_m = m.number("moment_arm_m", "metres");
    act.mount_distance_m = m.number("mount_distance_m", "metres");
    act.lever_angle_offset_rad = m.number("lever_angle_offset_rad", "rad");
  } else {
    m.fail("type", "expected rotary or linear, got '" + type + "'");
  }
  m.finish();
  return act;
}

// The parts every joint has, arm or hand: limits, default, link, actuator, sensors.
void readJointBody(const core::YamlMap& m, Joint& joint, const std::filesystem::path& file) {
  const core::YamlMap lim = m.map("limits");
  joint.limits.min_rad = lim.number("min_rad", "rad");
  joint.limits.max_rad = lim.number("max_rad", "rad");
  joint.limits.velocity_radps = lim.number("velocity_radps", "rad/s");
  joint.limits.torque_nm = lim.number("torque_nm", "N m");
  lim.finish();
  joint.default_rad = m.number("default_rad", "rad");

  const core::YamlMap link = m.map("link");
  joint.inertial = readInertial(link);
  joint.geometry = readGeometry(link.map("geometry"), file);
  link.finish();

  joint.actuator = readActuator(m.map("actuator"));

  const core::YamlMap sensors = m.map("sensors");
  const core::YamlMap pot = sensors.map("potentiometer");
  joint.potentiometer.slope_rad_per_count = pot.number("slope_rad_per_count", "rad per count");
  joint.potentiometer.offset_counts = pot.number("offset_counts", "counts");
  joint.potentiometer.polarity = pot.integer("polarity");
  joint.potentiometer.joint_offset_rad = pot.number("joint_offset_rad", "rad");
  joint.potentiometer.bits = pot.integer("bits");
  pot.finish();
  const core::YamlMap torque = sensors.map("torque");
  joint.torque_sensor.slope_nm_per_count = torque.number("slope_nm_per_count", "N m per count");
  joint.torque_sensor.offset_counts = torque.number("offset_counts", "counts");
  joint.torque_sensor.bits = torque.integer("bits");
  torque.finish();
  const core::YamlMap command = sensors.map("torque_command");
  joint.torque_command.slope_nm_per_count = command.number("slope_nm_per_count", "N m per count");
  joint.torque_command.offset_counts = command.number("offset_counts", "counts");
  joint.torque_command.bits = command.integer("bits");
  command.finish();
  sensors.finish();
}

int findJoint(const ArmModel& model, const core::YamlMap& m, std::string_view key) {
  const std::string name = m.string(key);
  const int index = model.jointIndex(name);
  if (index < 0) m.fail(key, "no joint named '" + name + "' (joints are listed before this key is used)");
  return index;
}

ArmModel buildModel(const core::YamlMap& root, const std::filesystem::path& source) {
  ArmModel model;
  model.source = source;
  const int version = root.integer("schema_version");
  if (version != kSchemaVersion) {
    root.fail("schema_version", "expected " + std::to_string(kSchemaVersion) + ", got " + std::to_string(version));
  }
  model.name = root.string("name");
  const std::string convention = root.string("dh_convention");
  if (convention != "modified") {
    root.fail("dh_convention", "expected 'modified' (Craig); got '" + convention + "'");
  }
  model.gravity_W_mps2 = root.vector3("gravity_mps2", "m/s^2, world frame");
  model.X_WB = readPose(root.map("base"));

  const core::YamlList joints = root.list("joints");
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const core::YamlMap m = joints.map(i);
    Joint joint;
    joint.name = m.string("name");
    joint.parent = static_cast<int>(i) - 1;
    const core::YamlMap dh = m.map("dh");
    DhParameters p;
    p.alpha_rad = dh.number("alpha_deg", "degrees") * kDegToRad;
    p.a_m = dh.number("a_m", "metres");
    p.d_m = dh.number("d_m", "metres");
    p.theta_offset_rad = dh.number("theta_offset_deg", "degrees") * kDegToRad;
    dh.finish();
    joint.dh = p;
    joint.X_PL0 = dhTransform(p);
    readJointBody(m, joint, source);
    m.finish();
    model.joints.push_back(std::move(joint));
  }

  if (const auto hand = root.optionalList("hand_joints")) {
    for (std::size_t i = 0; i < hand->size(); ++i) {
      const core::YamlMap m = hand->map(i);
      Joint joint;
      joint.name = m.string("name");
      joint.is_hand = true;
      joint.parent = findJoint(model, m, "parent");
      joint.X_PL0 = readPose(m.map("origin"));
      readJointBody(m, joint, source);
      m.finish();
      model.joints.push_back(std::move(joint));
    }
  }

  const core::YamlMap tool = root.map("tool");
  model.tool_link = findJoint(model, tool, "link");
  model.X_LT.translation() = tool.vector3("translation_m", "metres");
  const Eigen::Vector3d rpy = tool.vector3("rpy_deg", "degrees") * kDegToRad;
  model.X_LT.linear() = rotationFromRpy(rpy.x(), rpy.y(), rpy.z());
  tool.finish();

  const core::YamlMap segments = root.map("segments");
  model.upper_arm_joint = findJoint(model, segments, "upper_arm_joint");
  model.forearm_joint = findJoint(model, segments, "forearm_joint");
  segments.finish();
  root.finish();
  return model;
}

}  // namespace

namespace {

ArmModel buildAndValidate(const core::YamlMap& root, const std::filesystem::path& source) {
  ArmModel model = buildModel(root, source);
  try {
    validateArmModel(model);
  } catch (const core::ConfigError& e) {
    // Semantic checks know the key path; find its line in the document.
    throw core::ConfigError(e.file(), e.keyPath(), e.message(), core::lineOfKeyPath(root.node(), e.keyPath()));
  }
  return model;
}

}  // namespace

ArmModel parseArmModel(std::string_view yaml_text, const std::filesystem::path& source) {
  return buildAndValidate(core::YamlMap::parse(yaml_text, source), source);
}

ArmModel loadArmModel(const std::filesystem::path& file) {
  return buildAndValidate(core::YamlMap::load(file), file);
}

int findJointByName(const std::vector<std::string_view>& joint_names, std::string_view name,
                    const std::filesystem::path& source) {
  std::string known;
  for (std::size_t i = 0; i < joint_names.size(); ++i) {
    const std::string_view full = joint_names[i];
    const std::string_view shortname = full.starts_with("R_") ? full.substr(2) : full;
    if (name == full || name == shortname) return static_cast<int>(i);
    known += (known.empty() ? "" : ", ") + std::string(shortname);
  }
  throw core::ConfigError(source, "joint", "unknown joint name '" + std::string(name) + "': expected one of " + known);
}

std::filesystem::path defaultArmModelPath() {
  return core::defaultConfigPath("dts_master.yaml");
}

}  // namespace fullarm::arm
