#pragma once
/// @file
/// The 1 kHz haptic tick: one @rt function on the path of docs/architecture.md,
///
///   read (the caller) -> input checks (supervisor) -> forward kinematics once -> local descent
///   of the tracked minima -> contact springs -> tailored Jacobian torques (Eq. 1-2) -> gravity
///   once -> stale-minima fade -> admittance controller (Eq. 3-7) -> output limits -> write (the
///   caller),
///
/// plus a fixed-size telemetry record. Full-arm and hand-only modes (the paper's two conditions:
/// in hand-only mode only the hand's minima make forces, and every link's contact depth and
/// duration is recorded). The tick also tracks how far each link has swept since the joint
/// angles of the last global query and flags a sweep beyond L - d_f: beyond it a new contact
/// could have come within d_f without a minimum to render it.
///
/// Model/Data split: TickModel is constant after makeTickModel(); TickData is sized once;
/// stepTick() allocates nothing and runs in bounded time. Everything a tick reads is in
/// TickInputs, so feeding the same inputs through a fresh TickData reproduces every output
/// bit for bit (replay).

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/controllers/arm_controller.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/minima.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/supervisor.hpp"

namespace fullarm::hil {

/// Largest number of minima the tick tracks (a larger global set keeps its closest ones).
inline constexpr int kMaxTrackedMinima = 128;

/// Constant description of the tick.
struct TickModel {
  const arm::ArmModel* model = nullptr;             ///< not owned
  const haptics::CollisionWorld* world = nullptr;  ///< not owned
  haptics::HapticsParams haptics;                   ///< mode, springs, d_f, L, local descent
  controllers::ArmControllerModel controller;
  SupervisorModel supervisor;
  arm::JointSelection device_joints;  ///< the I/O device's joints
  /// For controller joint k, its position among the device joints.
  std::array<int, controllers::kMaxControlledJoints> device_of_controller{};
  /// Configuration of the joints the device does not read (the hand joints) [rad].
  Eigen::VectorXd fixed_posture;
  double period_s = 1e-3;
  /// Sweep bound of each link: the largest distance of its geometry (capsule or mesh) from its
  /// frame origin [m].
  std::array<double, arm::kMaxJoints> link_extent_m{};
  /// Flag a link whose sweep since the last query exceeds this (L - d_f) [m].
  double sweep_limit_m = 0.0;
};

/// Builds the tick for a device with joints `device_joints`: the controller of `gains`, the
/// supervisor of `supervisor` with the gains' valve limits, `haptics` (its mode is the tick's).
/// `model` and `world` must outlive the tick.
/// @throws core::ConfigError / std::invalid_argument when a controlled joint is not a device
///   joint, the period disagrees with the gains', or the world was built for another model
[[nodiscard]] TickModel makeTickModel(const arm::ArmModel& model, const haptics::CollisionWorld& world,
                                      const haptics::HapticsParams& haptics, const controllers::GainsConfig& gains,
                                      const SupervisorParams& supervisor, const arm::JointSelection& device_joints,
                                      const Eigen::VectorXd& fixed_posture);

/// A set of minima from the global search, as the tick adopts it.
struct MinimaDelivery {
  std::int64_t set_id = 0;                        ///< increases per set
  std::span<const haptics::LocalMinimum> minima;  ///< at most kMaxTrackedMinima are kept
  /// Joint angles the search used (configuration vector, model order) [rad].
  std::span<const double> query_q_rad;
};

/// Everything one tick reads.
struct TickInputs {
  const JointSample* sample = nullptr;  ///< the device's reading (required)
  core::RtStatus device_status;         ///< the status of that read
  const MinimaDelivery* minima = nullptr;  ///< a new set to adopt this tick, or nullptr
  SupervisorRequests requests;
};

/// Fixed-size record of one tick (trivially copyable): what a run log and a report need.
struct TickTelemetry {
  std::uint64_t tick = 0;
  double t_s = 0.0;          ///< tick time (tick x period) [s]
  double sample_t_s = 0.0;   ///< device time of the reading [s]
  std::uint64_t sample_sequence = 0;
  int num_device_joints = 0;
  int num_config = 0;
  std::array<double, arm::kMaxJoints> q_rad{};              ///< device order
  std::array<double, arm::kMaxJoints> tau_load_cell_nm{};   ///< device order
  std::array<double, arm::kMaxJoints> valve_v{};            ///< device order, after the limits
  std::array<double, arm::kMaxJoints> tau_contact_nm{};     ///< model order, after the fade
  std::array<double, arm::kMaxJoints> tau_gravity_nm{};     ///< model order
  /// Per link: smallest tracked distance [m] (infinity: none), depth d_f - d when in contact.
  std::array<double, arm::kMaxJoints> link_min_distance_m{};
  std::array<double, arm::kMaxJoints> link_depth_m{};
  std::array<double, arm::kMaxJoints> link_sweep_m{};  ///< sweep since the last query [m]
  /// Per link: the summed rendered contact force, world frame [N] (before the fade).
  std::array<std::array<double, 3>, arm::kMaxJoints> link_force_W_n{};
  std::array<double, arm::kMaxJoints> link_contact_s{};      ///< length of the current contact [s]
  std::array<double, arm::kMaxJoints> link_penetration_s{};  ///< summed penetration time [s]
  std::uint32_t link_contact_mask = 0;      ///< links closer than d_f
  std::uint32_t link_penetration_mask = 0;  ///< links touching an object (distance 0)
  std::uint32_t sweep_exceeded_mask = 0;    ///< links whose sweep exceeds L - d_f
  int tracked_minima = 0;
  int active_springs = 0;
  std::int64_t minima_set_id = -1;  ///< newest adopted set (-1: none yet)
  bool adopted_this_tick = false;
  double minima_age_s = 0.0;        ///< time since that set arrived [s]
  double contact_scale = 1.0;       ///< the fade of stale minima
  SupervisorState supervisor_state = SupervisorState::kStartup;
  SupervisorCause trip_cause = SupervisorCause::kNone;
  bool forces_allowed = false;
  std::uint32_t controller_faults = 0;
  int num_events = 0;
  std::array<SupervisorEvent, kMaxEventsPerTick> events{};
};

/// State and scratch of the tick, sized once for its model.
struct TickData {
  explicit TickData(const TickModel& model);

  arm::ArmData fk;             ///< the tick's one kinematics and gravity pass
  arm::ArmData query_fk;       ///< link frames at the joint angles of the adopted set's query
  haptics::ContactData contact;
  controllers::ArmControllerData control;
  SupervisorData supervisor;
  std::vector<haptics::LocalMinimum> tracked;  ///< capacity kMaxTrackedMinima, first num_tracked valid
  int num_tracked = 0;
  Eigen::VectorXd q;               ///< configuration [rad]
  Eigen::VectorXd tau_contact_nm;  ///< contact torques after the fade [N m]
  controllers::ControlVector load_cells_nm, valve_controller_v;
  IoVector valve_v;  ///< device order
  std::uint64_t tick = 0;
  std::int64_t minima_set_id = -1;
  double minima_age_s = 0.0;
  bool have_query = false;
  std::array<double, arm::kMaxJoints> sweep_m{};
  bool controller_running = false;
};

/// Back to the start: no minima, supervisor in start-up, controller unconfigured. @rt
void resetTick(const TickModel& tick, TickData& data) noexcept;

/// One tick. Writes the valve commands to put out (device order) into `valve_v` and the tick's
/// record into `telemetry`. The valves are at null unless the supervisor is running (start-up
/// guard done, no trip); a trip latches until inputs.requests.reset_command.
/// @rt
void stepTick(const TickModel& tick, TickData& data, const TickInputs& inputs, IoVector& valve_v,
              TickTelemetry& telemetry) noexcept;

}  // namespace fullarm::hil
