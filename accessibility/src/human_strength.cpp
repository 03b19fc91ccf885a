#include "fullarm/accessibility/human_strength.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::accessibility {
namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

std::vector<double> numberList(const core::YamlMap& m, std::string_view key, std::string_view what) {
  (void)m.list(key);  // marks the key read and checks that it is a list
  const YAML::Node values = m.node()[std::string(key)];
  if (values.size() == 0) m.fail(key, "expected a list of " + std::string(what) + ", got an empty list");
  std::vector<double> out;
  for (std::size_t k = 0; k < values.size(); ++k) {
    double value = 0.0;
    try {
      value = values[k].as<double>();
    } catch (const YAML::Exception&) {
      value = std::numeric_limits<double>::quiet_NaN();
    }
    if (!std::isfinite(value)) {
      m.fail(key, "element " + std::to_string(k) + " is not a finite number (" + std::string(what) + ")");
    }
    out.push_back(value);
  }
  return out;
}

int jointByName(const core::YamlMap& m, std::string_view key, const arm::ArmModel& model) {
  const std::string name = m.string(key);
  const int j = model.jointIndex(name);
  if (j < 0) m.fail(key, "joint '" + name + "' is not in the arm model '" + model.name + "'");
  return j;
}

JointAction readAction(const core::YamlMap& m, const arm::ArmModel& model) {
  JointAction a;
  a.action = m.string("action");
  a.torque_nm = m.number("torque_nm", "N m");
  if (!(a.torque_nm > 0.0)) {
    m.fail("torque_nm", "expected a maximal torque > 0 N m, got " + std::to_string(a.torque_nm));
  }
  if (const auto list = m.optionalList("posture")) {
    for (std::size_t i = 0; i < list->size(); ++i) {
      const core::YamlMap p = list->map(i);
      PostureFactor f;
      f.joint = jointByName(p, "joint", model);
      std::vector<double> angle_deg = numberList(p, "angle_deg", "joint angles in degrees");
      f.factor = numberList(p, "factor", "strength factors");
      if (f.factor.size() != angle_deg.size()) {
        p.fail("factor", "expected " + std::to_string(angle_deg.size()) + " factors (one per angle_deg), got " +
                             std::to_string(f.factor.size()));
      }
      for (std::size_t k = 0; k < angle_deg.size(); ++k) {
        if (k > 0 && !(angle_deg[k] > angle_deg[k - 1])) {
          p.fail("angle_deg", "expected strictly increasing angles, got " + std::to_string(angle_deg[k - 1]) +
                                  " then " + std::to_string(angle_deg[k]));
        }
        if (!(f.factor[k] > 0.0)) {
          p.fail("factor",
                 "element " + std::to_string(k) + " is " + std::to_string(f.factor[k]) + ", expected a factor > 0");
        }
        f.angle_rad.push_back(angle_deg[k] * kDegToRad);
      }
      p.finish();
      a.posture.push_back(std::move(f));
    }
  }
  m.finish();
  return a;
}

SegmentSpan readSpan(const core::YamlMap& m, const arm::ArmModel& model) {
  const std::string span = m.string("along");
  if (span == "upper_arm") {
    if (model.upper_arm_joint < 0) m.fail("along", "the arm model '" + model.name + "' names no upper-arm joint");
    return SegmentSpan::kUpperArm;
  }
  if (span == "forearm") {
    if (model.forearm_joint < 0) m.fail("along", "the arm model '" + model.name + "' names no forearm joint");
    return SegmentSpan::kForearm;
  }
  if (span == "hand") {
    if (model.tool_link < 0) m.fail("along", "the arm model '" + model.name + "' has no tool link");
    return SegmentSpan::kHand;
  }
  m.fail("along", "expected upper_arm, forearm or hand, got '" + span + "'");
}

HumanArm buildHumanArm(const core::YamlMap& root, const arm::ArmModel& model) {
  HumanArm human;
  human.source = root.file();
  const int version = root.integer("schema_version");
  if (version != 1) root.fail("schema_version", "expected 1, got " + std::to_string(version));
  human.body_mass_kg = root.number("body_mass_kg", "kg");
  if (!(human.body_mass_kg > 0.0)) {
    root.fail("body_mass_kg", "expected a body mass > 0 kg, got " + std::to_string(human.body_mass_kg));
  }
  human.strength_scale = root.number("strength_scale");
  if (!(human.strength_scale > 0.0)) {
    root.fail("strength_scale", "expected a factor > 0, got " + std::to_string(human.strength_scale));
  }
  const core::YamlList joints = root.list("joints");
  if (joints.size() == 0) root.fail("joints", "expected at least one joint");
  std::vector<bool> seen(static_cast<std::size_t>(model.numJoints()), false);
  int previous = -1;
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const core::YamlMap m = joints.map(i);
    JointStrength js;
    js.joint = jointByName(m, "name", model);
    if (seen[static_cast<std::size_t>(js.joint)]) m.fail("name", "joint '" + m.string("name") + "' is listed twice");
    if (js.joint < previous) m.fail("name", "expected the joints in the arm model's order");
    seen[static_cast<std::size_t>(js.joint)] = true;
    previous = js.joint;
    js.positive = readAction(m.map("positive"), model);
    js.negative = readAction(m.map("negative"), model);
    m.finish();
    human.joints.push_back(std::move(js));
  }
  const core::YamlList segments = root.list("segments");
  for (std::size_t i = 0; i < segments.size(); ++i) {
    const core::YamlMap m = segments.map(i);
    HumanSegment s;
    s.name = m.string("name");
    s.span = readSpan(m, model);
    s.mass_fraction = m.number("mass_fraction");
    if (!(s.mass_fraction >= 0.0 && s.mass_fraction < 1.0)) {
      m.fail("mass_fraction", "expected a fraction of the body mass in [0, 1), got " + std::to_string(s.mass_fraction));
    }
    s.com_fraction = m.number("com_fraction");
    if (!(s.com_fraction >= 0.0 && s.com_fraction <= 1.0)) {
      m.fail("com_fraction", "expected a fraction of the segment in [0, 1], got " + std::to_string(s.com_fraction));
    }
    m.finish();
    human.segments.push_back(std::move(s));
  }
  root.finish();
  return human;
}

double interpolate(const PostureFactor& f, double angle_rad) {
  const std::vector<double>& x = f.angle_rad;
  if (angle_rad <= x.front()) return f.factor.front();
  if (angle_rad >= x.back()) return f.factor.back();
  std::size_t k = 1;
  while (x[k] < angle_rad) ++k;
  const double t = (angle_rad - x[k - 1]) / (x[k] - x[k - 1]);
  return f.factor[k - 1] + t * (f.factor[k] - f.factor[k - 1]);
}

}  // namespace

std::vector<int> HumanArm::jointIndices() const {
  std::vector<int> out;
  out.reserve(joints.size());
  for (const JointStrength& j : joints) out.push_back(j.joint);
  return out;
}

HumanArm loadHumanArm(const std::filesystem::path& file, const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::load(file);
  return core::withKeyPathLines(root, [&] { return buildHumanArm(root, model); });
}

HumanArm parseHumanArm(std::string_view yaml_text, const std::filesystem::path& file, const arm::ArmModel& model) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, file);
  return core::withKeyPathLines(root, [&] { return buildHumanArm(root, model); });
}

std::filesystem::path defaultHumanArmPath() {
  return core::defaultConfigPath("human_arm.yaml");
}

double postureFactor(const JointAction& action, const Eigen::VectorXd& q) {
  double factor = 1.0;
  for (const PostureFactor& f : action.posture) factor *= interpolate(f, q[f.joint]);
  return factor;
}

void computeTorqueLimits(const HumanArm& human, const Eigen::VectorXd& q, Eigen::VectorXd& tau_min_nm,
                         Eigen::VectorXd& tau_max_nm) {
  const auto n = static_cast<Eigen::Index>(human.joints.size());
  tau_min_nm.resize(n);
  tau_max_nm.resize(n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const JointStrength& j = human.joints[static_cast<std::size_t>(i)];
    tau_max_nm[i] = human.strength_scale * j.positive.torque_nm * postureFactor(j.positive, q);
    tau_min_nm[i] = -human.strength_scale * j.negative.torque_nm * postureFactor(j.negative, q);
  }
}

Eigen::Vector3d segmentCom(const arm::ArmModel& model, const HumanSegment& segment, int& link) {
  Eigen::Vector3d proximal = Eigen::Vector3d::Zero();
  Eigen::Vector3d distal = Eigen::Vector3d::Zero();
  if (segment.span == SegmentSpan::kHand) {
    link = model.tool_link;
    distal = model.X_LT.translation();
  } else {
    link = segment.span == SegmentSpan::kUpperArm ? model.upper_arm_joint : model.forearm_joint;
    const auto& dh = model.joints[static_cast<std::size_t>(link)].dh;
    proximal = Eigen::Vector3d(0.0, 0.0, dh ? -dh->d_m : 0.0);
  }
  return proximal + segment.com_fraction * (distal - proximal);
}

Eigen::VectorXd computeHumanGravityTorques(const arm::ArmModel& model, const HumanArm& human, const arm::ArmData& fk) {
  // V = -sum_k m_k g . p_k(q), so dV/dq = -sum_k J_k^T m_k g (J_k: linear Jacobian of COM k).
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(model.numJoints());
  arm::PointJacobian J;
  for (const HumanSegment& s : human.segments) {
    int link = -1;
    const Eigen::Vector3d com_L = segmentCom(model, s, link);
    const Eigen::Vector3d com_W = arm::pointInWorld(fk, link, com_L);
    arm::computePointJacobian(model, fk, link, com_W, J);
    const double mass_kg = s.mass_fraction * human.body_mass_kg;
    tau -= J.topRows<3>().transpose() * (mass_kg * model.gravity_W_mps2);
  }
  return tau;
}

}  // namespace fullarm::accessibility
