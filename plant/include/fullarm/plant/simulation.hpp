#pragma once
/// @file
/// A plant run: one joint or the whole arm driven by a named command signal for a duration at a
/// fixed control period, recorded as one trace per active joint with the solver statistics, and
/// the trace-to-CSV writer. Used by `fullarm plant simulate` and the plant step of `fullarm demo`.

#include <filesystem>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/progress.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/joint_params.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::plant {

/// How far a chamber pressure may pass the supply or return pressure (what the check valves
/// need to pass their flow) before a run fails [Pa].
inline constexpr double kPressureMargin_pa = 0.5e6;
/// How far a joint may pass its hard stop before a run fails [deg].
inline constexpr double kStopOvershootLimit_deg = 0.5;

/// Unit of a joint's command.
enum class CommandUnit {
  kVolt,         ///< valve voltage (valve-voltage input mode)
  kNewtonMetre,  ///< desired torque (torque-loop input mode) or an ideal torque source's torque
};

/// The unit `joint` takes its command in.
[[nodiscard]] CommandUnit commandUnit(const JointParams& joint) noexcept;

/// A named command signal for a plant run.
struct InputSignal {
  /// "chirp", "step", "sine", "multisine" (plant::SignalKind), or a command table: a CSV file
  /// whose name ends in ".csv" (loadCommandCsv).
  std::string name = "chirp";
  /// Amplitude of a generated signal in command units (V, or N m in torque-loop mode); unset:
  /// each joint's full scale (fullScaleCommand).
  std::optional<double> amplitude;
  double frequency_hz = 1.0;  ///< sine frequency [Hz]
  double start_hz = 0.5;      ///< chirp start / multisine fundamental [Hz]
  double stop_hz = 80.0;      ///< chirp stop / highest multisine harmonic [Hz]
};

/// Command of active joint `joint` (index into the run's joints) at time `t_s`; the plant holds
/// it over the control period that starts at `t_s`.
using CommandFunction = std::function<double(std::size_t joint, double t_s)>;

/// What one active joint did: the state at each sample time t_i = i dt (i = 0 .. N, N = round(
/// duration / dt)) with the command applied over [t_i, t_i + dt). A run that stops on a solver
/// failure ends at the last state reached.
struct JointTrace {
  std::string joint;                                        ///< model name, e.g. "R_EB"
  CommandUnit command_unit = CommandUnit::kVolt;            ///< unit of `command`
  std::vector<double> time_s;                               ///< t_i [s]
  std::vector<double> command;                              ///< command over [t_i, t_i + dt) (V or N m)
  std::vector<double> q_rad;                                ///< joint angle [rad]
  std::vector<double> qd_radps;                             ///< joint velocity [rad/s]
  std::vector<double> tau_measured_nm;                      ///< load-cell torque as read (filtered, quantised) [N m]
  std::vector<double> p_a_pa;                               ///< chamber A pressure [Pa]
  std::vector<double> p_b_pa;                               ///< chamber B pressure [Pa]
  std::vector<double> spool_fraction;                       ///< spool position, a fraction of full opening
  double p_min_pa = std::numeric_limits<double>::max();     ///< lowest chamber pressure [Pa]
  double p_max_pa = std::numeric_limits<double>::lowest();  ///< highest chamber pressure [Pa]
  double stop_overshoot_rad = 0.0;  ///< largest excursion beyond the joint's range (0: none) [rad]
};

/// Outcome of simulate().
struct SimulationResult {
  std::vector<JointTrace> traces;  ///< one per active joint, in the order of the run's joints
  SolverStats stats;               ///< integrator counters over the run
  bool solver_ok = true;           ///< false when a step failed (the run stopped there)
  std::string solver_error;        ///< the integrator's message when !solver_ok
  double wall_s = 0.0;             ///< wall-clock time of the run [s]
  double simulated_s = 0.0;        ///< plant time reached [s]
  /// Every chamber pressure within [return - kPressureMargin_pa, supply + kPressureMargin_pa].
  bool pressures_ok = true;
  /// No joint past its hard stop by more than kStopOvershootLimit_deg.
  bool stops_held = true;

  /// Simulated over wall-clock time.
  [[nodiscard]] double realTimeFactor() const noexcept;
  /// solver_ok && pressures_ok && stops_held.
  [[nodiscard]] bool passed() const noexcept { return solver_ok && pressures_ok && stops_held; }
};

/// Full-scale command of a joint: 1 / amplifier gain volts in valve-voltage mode, the arm
/// model's joint torque limit in torque-loop mode.
[[nodiscard]] double fullScaleCommand(const JointParams& joint, const arm::ArmModel& model);

/// The command of `input` for each of `joints`. A generated signal (signalValue) runs with its
/// amplitude (default: each joint's full scale), chirp sweep time `duration_s` and, for a step,
/// the step at min(0.1 s, duration_s / 10). A command table drives each joint with its
/// `command_<joint>` column (model or short name, e.g. `command_R_EB` or `command_EB`), else the
/// first column.
/// @throws std::invalid_argument for an unknown signal name, or stop_hz <= start_hz for a chirp
///   or multisine
/// @throws std::runtime_error for a command table that cannot be read (loadCommandCsv)
[[nodiscard]] CommandFunction makeCommand(const InputSignal& input, const arm::ArmModel& model,
                                          const std::vector<JointParams>& joints, double duration_s);

/// Runs the plant of `config` on `model` with `joints` active (the others locked at the model's
/// default posture), from the default posture at rest (ArmPlant::reset), for `duration_s` at the
/// control period `dt_s`: at each t_i it records the state and the command, then steps one period.
/// The traces are reserved up front: 8 doubles per sample and joint, (duration / dt + 1) samples.
/// Reports the periods as units of `progress` (a task "plant simulate") unless it is null.
/// @throws core::ConfigError for joints the plant cannot configure (ArmPlant::configure)
[[nodiscard]] SimulationResult simulate(const arm::ArmModel& model, const PlantConfig& config,
                                        const std::vector<JointParams>& joints, const CommandFunction& command,
                                        double duration_s, double dt_s, core::Progress* progress = nullptr);

/// Writes a trace as CSV: a header row `time_s,command_v,q_rad,qd_rad_s,tau_measured_nm,p_a_pa,
/// p_b_pa,spool_fraction` (`command_nm` for a command in N m), then one row per sample (10
/// significant digits). The spool position is a fraction of full opening.
/// @throws std::runtime_error naming the file when it cannot be written
void writeTraceCsv(const JointTrace& trace, const std::filesystem::path& file);

}  // namespace fullarm::plant
