#pragma once
/// @file
/// An experiment log as an LCM log: the same rows as the CSV log (signal_csv.hpp), in the format
/// of the loop's run logs, readable by LCM's own tools (`lcm-logplayer`, `lcm-spy`) and by
/// `fullarm identify --log`.
///
/// The first event, on channel FULLARM_IDENT_EXPERIMENT, is an ident_experiment_t: the program
/// and command that wrote the log, the back-end, the driven joint, the control period and the
/// held joints' names. Then one ident_sample_t per row on FULLARM_IDENT_SAMPLE, seq 0, 1, 2, ...
/// Events on other channels (a log recorded with `lcm-logger` beside other traffic) are skipped.
/// Logs written before the chamber pressures were logged (the earlier layouts of both types,
/// `ident_experiment_v1_t` and `ident_sample_v1_t`, told apart by their type hash) read as logs
/// without pressures.
///
/// Reading is strict: a log whose first experiment event is missing or is not the first sample's
/// predecessor, a payload that does not decode, a lost sample (a gap in seq), a sample whose held
/// or pressure count differs from the header's, a non-finite value or a time that does not strictly increase
/// is a hil::RunLogError naming the file, the byte offset and what was expected. A truncated last
/// event (a log cut short while it was written) is dropped and said in the warning.

#include <filesystem>
#include <string>

#include "fullarm/identification/signal_csv.hpp"

namespace fullarm::identification {

namespace channel {
inline constexpr const char* kIdentExperiment = "FULLARM_IDENT_EXPERIMENT";
inline constexpr const char* kIdentSample = "FULLARM_IDENT_SAMPLE";
}  // namespace channel

/// What an experiment log says of itself besides its rows.
struct ExperimentLogInfo {
  std::string command_line;      ///< the command that wrote it
  std::string source;            ///< the back-end (sim, fakedaq, comedi, lcm)
  std::string joint;             ///< the driven joint
  double sample_period_s = 0.0;  ///< control period [s]
  std::string fullarm_version;   ///< set by the reader (the writer puts its own)
};

/// Writes `table` (kExperimentColumns, the chamber pressures kPressureColumns where logged, then
/// `held_<joint>_rad` per held joint, as runExperiment logs it) as an LCM log.
/// @throws std::invalid_argument for a table without the experiment columns, one chamber pressure
///   without the other, columns of unequal length or other extra columns; hil::RunLogError naming the file when it
///   cannot be written
void writeExperimentLcmLog(const std::filesystem::path& file, const SignalTable& table, const ExperimentLogInfo& info);

/// An experiment log read back.
struct ExperimentLcmLog {
  SignalTable table;       ///< the rows, as readSignalCsv would give them from the CSV log
  ExperimentLogInfo info;  ///< the header's description
  std::string warning;     ///< a truncated last event, dropped; empty when none
  long long skipped = 0;   ///< events on other channels
};

/// Reads an experiment LCM log (strictly: see the file comment).
/// @throws hil::RunLogError naming the file, and for an event its byte offset
[[nodiscard]] ExperimentLcmLog readExperimentLcmLog(const std::filesystem::path& file);

/// True when `file` starts with the LCM log's event marker (otherwise it is read as CSV).
/// @throws hil::RunLogError naming the file when it cannot be opened
[[nodiscard]] bool isLcmLog(const std::filesystem::path& file);

}  // namespace fullarm::identification
