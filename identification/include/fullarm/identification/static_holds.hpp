#pragma once
/// @file
/// Static holds through an I/O device: the experiment behind the gravity fit (gravity.hpp).
///
/// Every joint of the device is held by a proportional position hold u = K (q_target - q) on
/// its valve command (the hold of experiment.hpp, here on every joint at once). For each posture
/// the target first moves smoothly (a cosine blend, over `move_s` or longer when the mean speed
/// of a joint's target would exceed `move_speed_radps`) from where it was to the posture plus
/// `approach_rad` on every joint, then to the posture itself; the arm settles and the readings
/// are averaged over a window. Then the same from below (the posture minus `approach_rad`).
/// Friction that holds a joint at rest acts against the last motion, so it has opposite signs on
/// the two sides and the mean of the two holds cancels it (combineSides).
///
/// The run stops early, outputs at their safe value, when a joint comes within a margin of its
/// limits, a joint is more than `max_error_rad` from its target, a reading is not finite or the
/// device fails. The holds before the stop are kept. A joint that starts inside the margin (an
/// arm resting at a stop) may move out of it on the first move: until that move ends it must
/// only come no closer to the limit than it started, less half the margin for the readings'
/// noise and the sag onto the stop while the holds take the load (a start beyond the limits
/// stops the run at once).
///
/// The log (writeStaticHoldsCsv) has one row per hold: `time_s` (end of the averaging window),
/// `posture_index`, `side_sign` (+1 approached from above, -1 from below), then `q_<joint>_rad`
/// and `tau_<joint>_nm` per device joint (the window means).

#include <Eigen/Core>
#include <filesystem>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "fullarm/arm/joint_selection.hpp"
#include "fullarm/hil/io_device.hpp"

namespace fullarm::identification {

struct StaticHold;

/// Settings of a static-hold run; the limit vectors follow the device's joint order.
struct StaticHoldOptions {
  double hold_gain_v_per_rad = 30.0;  ///< K of every joint's position hold
  double approach_rad = 0.05;         ///< each side starts this far from the posture (every joint)
  double move_s = 1.0;                ///< the target's move to the approach start (at least)
  double move_speed_radps = 0.5;      ///< ... and longer when a joint's target would move faster
  double approach_s = 0.5;            ///< the target's move from the approach start to the posture
  double settle_s = 1.0;              ///< wait at the posture before averaging
  double average_s = 0.5;             ///< averaging window
  double limit_margin_rad = 0.02;     ///< stop when a joint comes this close to a limit
  double max_error_rad = 0.2;         ///< stop when a joint is this far from its target
  std::vector<double> min_rad;        ///< lower limit of every device joint
  std::vector<double> max_rad;        ///< upper limit of every device joint
  /// Called before every read of the run (empty: none): the pacing of a real board, as in
  /// ExperimentOptions::before_read (false stops the run).
  std::function<bool()> before_read;
  /// Called with each hold as it is taken (empty: none): a command's progress line.
  std::function<void(const StaticHold&)> on_hold;
};

/// One averaged hold.
struct StaticHold {
  int posture_index = 0;   ///< which posture of the run
  int side = 0;            ///< +1 approached from above, -1 from below
  double time_s = 0.0;     ///< device time at the end of the averaging window
  Eigen::VectorXd q_rad;   ///< mean joint angles, device order
  Eigen::VectorXd tau_nm;  ///< mean load-cell torques, device order
};

/// Outcome of a run.
struct StaticHoldRun {
  std::vector<StaticHold> holds;  ///< in the order taken: posture 0 from above, from below, posture 1 ...
  bool completed = false;         ///< every posture was held from both sides
  std::string stop_reason;        ///< why it stopped early (empty when completed)
};

/// Runs the holds at `postures_rad` (device order): configures the device if needed, activates
/// it, holds each posture from above then from below, and deactivates it whatever happens.
/// @throws std::invalid_argument for limits or postures of the wrong size, non-positive times,
///   or a posture whose approach (posture +- approach_rad) is not inside the limits less the margin
/// @throws hil::DeviceError when the device cannot be read before the holds start
[[nodiscard]] StaticHoldRun runStaticHolds(hil::IoDevice& device, const std::vector<Eigen::VectorXd>& postures_rad,
                                           const StaticHoldOptions& options);

/// A posture's two holds averaged: the angles and torques with the friction at rest cancelled.
struct CombinedHold {
  int posture_index = 0;
  Eigen::VectorXd q_rad;   ///< mean of the two sides' angles, device order
  Eigen::VectorXd tau_nm;  ///< mean of the two sides' torques, device order
};

/// Pairs the holds of each posture (one from above, one from below) and averages them, in order
/// of posture index.
/// @throws std::invalid_argument naming the posture when it lacks a side or has one twice
[[nodiscard]] std::vector<CombinedHold> combineSides(const std::vector<StaticHold>& holds);

/// Device-order angles scattered into the configuration `base_configuration` (the joints the
/// device does not drive keep their angles there): the postures gravityRegressor takes.
[[nodiscard]] Eigen::VectorXd holdConfiguration(const Eigen::VectorXd& base_configuration,
                                                const arm::JointSelection& device_joints,
                                                const Eigen::VectorXd& q_device_rad);

/// Writes the holds log; `joint_names` name the device joints (in device order).
/// @throws std::invalid_argument for a hold of the wrong size; std::runtime_error naming the
///   file when it cannot be written
void writeStaticHoldsCsv(const std::filesystem::path& file, const std::vector<StaticHold>& holds,
                         const std::vector<std::string>& joint_names);

/// Parses a holds log (strictly: the checks of parseSignalCsv, and a posture index that is not a
/// non-negative integer or a side that is not +1 or -1 is an error naming the line).
/// @throws CsvFormatError naming `source`, the line and the value
[[nodiscard]] std::vector<StaticHold> parseStaticHoldsCsv(std::string_view text, const std::string& source,
                                                          const std::vector<std::string>& joint_names);

/// Reads a holds log file (see parseStaticHoldsCsv).
/// @throws CsvFormatError (also when the file cannot be opened)
[[nodiscard]] std::vector<StaticHold> readStaticHoldsCsv(const std::filesystem::path& file,
                                                         const std::vector<std::string>& joint_names);

}  // namespace fullarm::identification
