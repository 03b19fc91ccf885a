#pragma once
/// @file
/// Contact springs on the tracked minima, joint torques by the DTS paper's tailored force
/// Jacobians (Eq. (1)-(2)), the hand-only baseline with per-link contact records, and the YAML
/// parameters (config/haptics.yaml). Every function here reads the forward kinematics the
/// caller has already computed (`const arm::ArmData&`) and computes contact only: the tick
/// computes the kinematics and the gravity torques once, in fullarm::arm.

#include <Eigen/Core>
#include <filesystem>
#include <span>
#include <string_view>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/rt_status.hpp"
#include "fullarm/haptics/local_descent.hpp"
#include "fullarm/haptics/minima.hpp"

namespace fullarm::haptics {

/// Which minima make forces: all of them (full-arm haptics) or only those on the hand links
/// (the paper's baseline; the other links' contacts are recorded, not rendered).
enum class RenderMode { kFullArm, kHandOnly };

/// Haptic rendering parameters. Load with loadHapticsParams(); validated (see
/// validateHapticsParams).
struct HapticsParams {
  double stiffness_npm = 2000.0;    ///< spring constant k per minimum [N/m]
  double damping_nspm = 0.0;        ///< damping on the approach rate [N s/m] (0: none)
  double force_threshold_m = 0.01;  ///< d_f: springs act for d < d_f [m]
  double cutoff_m = 0.03;           ///< L: global search cutoff, > d_f [m]
  double prune_radius_m = 0.02;     ///< r: endpoint pruning radius [m]
  /// Scale each spring by its share (d_f - d_i) / sum (d_f - d_j) of its patch, so a patch
  /// renders like one spring whatever its number of minima (see computeContactForces).
  bool normalise_per_patch = false;
  double patch_radius_m = 0.05;            ///< minima whose link points are this close share a patch [m]
  double max_force_per_minimum_n = 200.0;  ///< saturation of each spring [N]
  /// p99 of the time from a posture to its minima reaching the tick [ms]: the global search's
  /// start period plus its p99 duration, as measured on the machine that runs it (the motion
  /// benchmark, BENCHMARKS.md) (YAML global_search.latency_p99_ms).
  double search_latency_p99_ms = 2.0;
  /// Largest speed of any point of any link while the arm is in use [m/s] (YAML
  /// global_search.max_link_speed_mps). With the latency it sets the smallest safe look-ahead:
  /// L - d_f >= max_link_speed_mps x search_latency_p99_ms (see minimumCutoffMargin).
  double max_link_speed_mps = 1.5;
  RenderMode mode = RenderMode::kFullArm;
  LocalDescentParams descent;
};

/// Reads and validates a haptics YAML file (strict: unknown keys are errors).
/// @throws core::ConfigError naming the file, key path and expected value
[[nodiscard]] HapticsParams loadHapticsParams(const std::filesystem::path& file);
/// core::defaultConfigPath("haptics.yaml"): the shipped parameters (source tree or install).
[[nodiscard]] std::filesystem::path defaultHapticsParamsPath();
/// Same from text; `file` is only used in error messages.
[[nodiscard]] HapticsParams parseHapticsParams(std::string_view yaml_text, const std::filesystem::path& file);
/// @throws core::ConfigError for non-positive stiffness, d_f >= L, negative damping, a
///   look-ahead L - d_f below minimumCutoffMargin (the message names both figures), ...
void validateHapticsParams(const HapticsParams& params, const std::filesystem::path& file);

/// The smallest safe look-ahead L - d_f [m]: the distance a link covers at max_link_speed_mps
/// during search_latency_p99_ms, so that a new minimum reaches the tick before the link, coming
/// from beyond the cutoff, closes in to the force threshold (DTS paper §3.2.1: the global search
/// must deliver minima before penetration).
[[nodiscard]] double minimumCutoffMargin(const HapticsParams& params) noexcept;

/// Contact statistics of one link (for the visual cue and the study statistics). "Contact"
/// means a minimum closer than d_f (inside the rendered skin); "penetration" means the link
/// mesh touches or intersects an object (distance 0).
struct LinkContactRecord {
  bool in_contact = false;
  bool penetrating = false;
  double min_distance_m = std::numeric_limits<double>::infinity();  ///< this tick
  double depth_m = 0.0;              ///< this tick: d_f - min distance, if in contact [m]
  double max_depth_m = 0.0;          ///< largest depth since reset [m]
  double contact_duration_s = 0.0;   ///< length of the current contact [s]
  double total_contact_s = 0.0;      ///< summed contact time since reset [s]
  double total_penetration_s = 0.0;  ///< summed penetration time since reset [s]
  int contact_onsets = 0;            ///< number of contacts started since reset
};

/// Results and scratch of the contact computation, sized once for a model and a maximum
/// number of minima (Model/Data split: nothing here resizes on the 1 kHz path).
struct ContactData {
  ContactData(const arm::ArmModel& model, int max_minima);

  std::vector<Eigen::Vector3d> f_W;            ///< force on the link at each minimum, world [N]
  std::vector<Eigen::Vector3d> p_W;            ///< contact point on the link, world [m]
  std::vector<double> stiffness_npm;           ///< stiffness used per minimum (after normalisation)
  std::vector<std::uint8_t> rendered;          ///< 1 if the minimum made a force
  std::vector<double> magnitude_n;             ///< scratch: spring magnitude before saturation [N]
  std::vector<int> patch_root;                 ///< scratch: patch (union-find) of each minimum
  std::vector<double> patch_weight;            ///< scratch: sum of (d_f - d) per patch root [m]
  /// Contact torque [N m], a configuration vector (size n, model order): the torque the
  /// environment applies to the links, positive toward +q, the sum of the tailored-Jacobian
  /// torques. What the plant and the arm controller receive as tau_contact_nm.
  Eigen::VectorXd tau_contact_nm;
  std::vector<LinkContactRecord> links;        ///< one per link
  std::vector<Eigen::Vector3d> link_force_W;   ///< scratch: summed force per link [N]
  std::vector<Eigen::Vector3d> link_moment_W;  ///< scratch: summed moment about o_n per link [N m]
  int active_springs = 0;
  /// Status of the last computeContactForces: not ok when an input was unusable (a non-finite
  /// minimum: kFaultNonFiniteInput; more minima than the capacity: kFaultCapacity; a bad link
  /// index: kFaultBadIndex; a non-positive tick period: kFaultOutOfRange). The contact torques
  /// are then zero (safe output) and the caller must report it.
  core::RtStatus status;
};

/// True for the tool link and the hand joints' links.
/// @rt
[[nodiscard]] bool isHandLink(const arm::ArmModel& model, int link) noexcept;

/// Spring forces on the minima and the per-link contact records.
/// For each minimum with d < d_f: |f| = k_eff (d_f - d) - b d_dot, clamped to
/// [0, max_force_per_minimum_n], along -u_W (away from the object), at the link point; d_dot
/// from previous_distance_m over dt_s. In hand-only mode only hand-link minima make forces.
/// @param fk forward kinematics at the current configuration (link frames)
/// @param dt_s tick period [s] (> 0) for durations and the damping rate
/// @rt
void computeContactForces(const HapticsParams& params, const arm::ArmModel& model, const arm::ArmData& fk,
                          std::span<const LocalMinimum> minima, double dt_s, ContactData& data) noexcept;

/// Adds the joint torques of force f_W applied at p_W on `link`, by the tailored force
/// Jacobian of the DTS paper: the force is moved to the origin of the contact link's joint
/// n, giving eta_c = (p_W - o_n) x f_W; Eq. (2) tau_n = z_n . eta_c; Eq. (1) for every joint i
/// that moves link n (its ancestors): tau_i = (z_i x b_i) . f_W + z_i . eta_c with
/// b_i = o_n - o_i. (Equal to J_c^T f for the point Jacobian at p_W.)
/// @param tau size model.numJoints(), accumulated into
/// @rt
void addTailoredJacobianTorques(const arm::ArmModel& model, const arm::ArmData& fk, int link,
                                const Eigen::Vector3d& p_W, const Eigen::Vector3d& f_W,
                                Eigen::Ref<Eigen::VectorXd> tau) noexcept;

/// Same with the force already moved to the joint origin o_n of `link`: force f_W and moment
/// eta_c about o_n (Eq. (1)-(2) take exactly these).
/// @rt
void addTailoredJacobianWrench(const arm::ArmModel& model, const arm::ArmData& fk, int link, const Eigen::Vector3d& f_W,
                               const Eigen::Vector3d& eta_c, Eigen::Ref<Eigen::VectorXd> tau) noexcept;

/// tau_contact_nm = sum of addTailoredJacobianTorques over the forces of computeContactForces, at
/// the kinematics in `fk` (computed once per tick by the caller; not recomputed here). Zero
/// contact torque when data.status is not ok.
/// @rt
void computeContactTorques(const arm::ArmModel& model, const arm::ArmData& fk, std::span<const LocalMinimum> minima,
                           ContactData& data) noexcept;

/// Clears the accumulated statistics of every link record.
void resetContactRecords(ContactData& data) noexcept;

}  // namespace fullarm::haptics
