#pragma once
/// @file
/// The scripted user (`fullarm run --user FILE`; schema in docs/hil.md, "Scripted user"): a hand
/// path through timed via points, the user's arm impedance at the hand, and the largest force
/// the user pushes with. The user pulls the exoskeleton along its path: at each control period
/// the force on the hand point is F = K (p_path(t) - p_hand) + B (v_path(t) - v_hand), cut to the
/// push force, and the user's joint torques are J_hand^T F. The shipped default
/// (config/user_reach_valve.yaml) reaches through the valve scene's opening.

#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/hil/simulated_arm.hpp"

namespace fullarm::hil {

/// One via point of the hand path.
struct ViaPoint {
  double t_s = 0.0;                                   ///< when the path passes it [s]
  Eigen::Vector3d p_S_m = Eigen::Vector3d::Zero();    ///< hand point in the scene frame [m]
};

/// A scripted user. Constant after loading.
struct ScriptedUserParams {
  std::filesystem::path source;
  std::string name;
  std::vector<ViaPoint> via_points;  ///< at least one, strictly increasing times
  double stiffness_npm = 300.0;      ///< user's arm stiffness at the hand [N/m]
  double damping_nspm = 30.0;        ///< user's arm damping at the hand [N s/m]
  double push_force_n = 15.0;        ///< largest force the user pushes with [N]
};

/// Reads a user file (strict).
/// @throws core::ConfigError naming the file, line, key path and what was expected
[[nodiscard]] ScriptedUserParams loadScriptedUser(const std::filesystem::path& file);
/// Same from text; `file` names the source in errors.
[[nodiscard]] ScriptedUserParams parseScriptedUser(std::string_view yaml_text, const std::filesystem::path& file);
/// core::defaultConfigPath("user_reach_valve.yaml").
[[nodiscard]] std::filesystem::path defaultScriptedUserPath();

/// The user as a SimulatedUser of the simulated arm.
class ScriptedUser final : public SimulatedUser {
 public:
  /// @param X_SW pose of the arm's world frame in the scene (haptics::armBasePose)
  ScriptedUser(const ScriptedUserParams& params, const arm::ArmModel& model, const Eigen::Isometry3d& X_SW);
  /// The path's hand point at time t, in the arm's world frame [m] (piecewise linear between
  /// via points; held at the ends). @rt
  [[nodiscard]] Eigen::Vector3d pathPoint(double t_s) const noexcept;
  /// The path's velocity at time t, world frame [m/s]. @rt
  [[nodiscard]] Eigen::Vector3d pathVelocity(double t_s) const noexcept;
  /// @rt
  void userTorques(double t_s, const arm::ArmData& fk, const Eigen::VectorXd& qd_radps,
                   Eigen::VectorXd& tau_user_nm) noexcept override;
  /// The force of the last userTorques() call, world frame [N].
  [[nodiscard]] const Eigen::Vector3d& lastForce() const noexcept { return force_W_; }
  [[nodiscard]] const ScriptedUserParams& params() const noexcept { return params_; }

 private:
  ScriptedUserParams params_;
  const arm::ArmModel& model_;
  std::vector<Eigen::Vector3d> p_W_;  // via points in the arm's world frame
  arm::PointJacobian jacobian_;
  Eigen::Vector3d force_W_ = Eigen::Vector3d::Zero();
};

}  // namespace fullarm::hil
