#include "fullarm/hil/scripted_user.hpp"

#include <cmath>

#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/data_paths.hpp"
#include "fullarm/core/yaml_reader.hpp"

namespace fullarm::hil {

namespace {

ScriptedUserParams readUser(const core::YamlMap& root) {
  ScriptedUserParams p;
  p.source = root.file();
  if (root.integer("schema_version") != 1) root.fail("schema_version", "expected 1");
  p.name = root.string("name");
  const core::YamlMap arm = root.map("arm_impedance");
  p.stiffness_npm = arm.number("stiffness_npm", "N/m");
  p.damping_nspm = arm.number("damping_nspm", "N s/m");
  if (!(p.stiffness_npm >= 0.0) || !std::isfinite(p.stiffness_npm)) arm.fail("stiffness_npm", "expected a value >= 0");
  if (!(p.damping_nspm >= 0.0) || !std::isfinite(p.damping_nspm)) arm.fail("damping_nspm", "expected a value >= 0");
  arm.finish();
  p.push_force_n = root.number("push_force_n", "N");
  if (!(p.push_force_n > 0.0) || !std::isfinite(p.push_force_n)) root.fail("push_force_n", "expected a value > 0 N");
  const core::YamlList via = root.list("hand_path");
  for (std::size_t i = 0; i < via.size(); ++i) {
    const core::YamlMap v = via.map(i);
    ViaPoint point;
    point.t_s = v.number("t_s", "s");
    point.p_S_m = v.vector3("hand_m", "metres");
    if (!std::isfinite(point.t_s) || point.t_s < 0.0) v.fail("t_s", "expected a time >= 0 s");
    if (!p.via_points.empty() && point.t_s <= p.via_points.back().t_s) {
      v.fail("t_s", "expected the via points in strictly increasing time");
    }
    v.finish();
    p.via_points.push_back(point);
  }
  if (p.via_points.empty()) root.fail("hand_path", "expected at least one via point");
  root.finish();
  return p;
}

}  // namespace

ScriptedUserParams parseScriptedUser(std::string_view yaml_text, const std::filesystem::path& file) {
  const core::YamlMap root = core::YamlMap::parse(yaml_text, file);
  return core::withKeyPathLines(root, [&] { return readUser(root); });
}

ScriptedUserParams loadScriptedUser(const std::filesystem::path& file) {
  const core::YamlMap root = core::YamlMap::load(file);
  return core::withKeyPathLines(root, [&] { return readUser(root); });
}

std::filesystem::path defaultScriptedUserPath() {
  return core::defaultConfigPath("user_reach_valve.yaml");
}

ScriptedUser::ScriptedUser(const ScriptedUserParams& params, const arm::ArmModel& model, const Eigen::Isometry3d& X_SW)
    : params_(params), model_(model) {
  const Eigen::Isometry3d X_WS = X_SW.inverse();
  for (const ViaPoint& v : params.via_points) p_W_.push_back(X_WS * v.p_S_m);
  jacobian_.resize(6, model.numJoints());
}

Eigen::Vector3d ScriptedUser::pathPoint(double t_s) const noexcept {
  const std::vector<ViaPoint>& v = params_.via_points;
  if (t_s <= v.front().t_s) return p_W_.front();
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (t_s < v[i].t_s) {
      const double s = (t_s - v[i - 1].t_s) / (v[i].t_s - v[i - 1].t_s);
      return p_W_[i - 1] + s * (p_W_[i] - p_W_[i - 1]);
    }
  }
  return p_W_.back();
}

Eigen::Vector3d ScriptedUser::pathVelocity(double t_s) const noexcept {
  const std::vector<ViaPoint>& v = params_.via_points;
  for (std::size_t i = 1; i < v.size(); ++i) {
    if (t_s >= v[i - 1].t_s && t_s < v[i].t_s) return (p_W_[i] - p_W_[i - 1]) / (v[i].t_s - v[i - 1].t_s);
  }
  return Eigen::Vector3d::Zero();
}

void ScriptedUser::userTorques(double t_s, const arm::ArmData& fk, const Eigen::VectorXd& qd_radps,
                               Eigen::VectorXd& tau_user_nm) noexcept {
  const Eigen::Vector3d p_hand = fk.X_WT.translation();
  arm::computePointJacobian(model_, fk, model_.tool_link, p_hand, jacobian_);
  const Eigen::Vector3d v_hand = jacobian_.topRows<3>() * qd_radps;
  Eigen::Vector3d f = params_.stiffness_npm * (pathPoint(t_s) - p_hand) + params_.damping_nspm * (pathVelocity(t_s) - v_hand);
  const double magnitude = f.norm();
  if (magnitude > params_.push_force_n) f *= params_.push_force_n / magnitude;
  force_W_ = f;
  tau_user_nm.noalias() = jacobian_.topRows<3>().transpose() * f;
}

}  // namespace fullarm::hil
