#pragma once
/// @file
/// The LCM log of a run and its replay (`fullarm run` writes it, `fullarm replay LOG` reads it).
///
/// A run log holds, through the transport's records and RunLogWriter (run_log.hpp): the run
/// header (the input files with their SHA-256, the I/O back-end, clock, mode, seed and loop
/// parameters), one joint_state_t per tick (the reading, the valve commands sent and the
/// tick's other inputs in `input_flags`, see kInputFlag*), one valve_command_t, one
/// haptic_status_t (contact torques, per-link forces and records) and every supervisor event,
/// and each minima set the tick adopted (with the tick that adopted it). That is every input of
/// every tick: replayLog() rebuilds the run's tick from the header's files, feeds the logged
/// inputs through it and compares every force, torque and valve command bit for bit.

#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fullarm/hil/log_records.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/run_log.hpp"
#include "fullarm/hil/spsc_ring.hpp"

namespace fullarm::hil {

/// joint_state_t.input_flags: bits 0-9 the joints read out of range; then the tick's requests.
inline constexpr std::uint32_t kInputFlagOutOfRangeMask = 0x3FFu;
inline constexpr std::uint32_t kInputFlagDeviceFault = 1u << 16;  ///< the read failed
inline constexpr std::uint32_t kInputFlagEstopCommand = 1u << 17;
inline constexpr std::uint32_t kInputFlagEstopSignal = 1u << 18;
inline constexpr std::uint32_t kInputFlagReset = 1u << 19;
inline constexpr std::uint32_t kInputFlagOverrunFault = 1u << 20;
inline constexpr std::uint32_t kInputFlagHeartbeatWatched = 1u << 21;
inline constexpr std::uint32_t kInputFlagHeartbeatBeat = 1u << 22;  ///< the heartbeat changed at this tick
inline constexpr std::uint32_t kInputFlagLinkLost = 1u << 23;  ///< the failed read was a lost link (kFaultLinkLost)
inline constexpr std::uint32_t kInputFlagPeerHeartbeatLost = 1u << 24;  ///< a peer node's heartbeat stopped

/// The flags of one tick's inputs; `previous_heartbeat` is the last tick's counter. @rt
[[nodiscard]] std::uint32_t encodeInputFlags(const RecordedTick& tick, std::uint64_t previous_heartbeat) noexcept;

/// Writes a run's log. The record calls are @rt (they only push into rings); the log is written
/// by the writer's own thread (threaded) or by pump() (lockstep).
class RunRecorder {
 public:
  /// Creates the log (an earlier file of that name is replaced at once, so a run that stops
  /// before its first tick does not leave another run's log behind); begin() writes its header.
  /// @throws RunLogError naming the file if it cannot be created
  RunRecorder(const std::filesystem::path& file, bool threaded);
  /// Writes the header (the run's inputs and, for remote I/O, what the node said it serves:
  /// call it after the device's configure()) and starts recording. Once, before the first tick.
  /// @throws std::logic_error when called again
  void begin(const HilSession& session, const std::string& command_line);
  ~RunRecorder();
  RunRecorder(const RunRecorder&) = delete;
  RunRecorder& operator=(const RunRecorder&) = delete;

  /// One tick: its inputs, its telemetry and what was written to the device. @rt
  void recordTick(const RecordedTick& inputs, const TickTelemetry& telemetry, const IoVector& written, bool safe_output,
                  std::int64_t utime_us) noexcept;
  /// A minima set adopted at `adopted_tick`. @rt
  void recordAdoptedSet(const MinimaSetRecord& set) noexcept;
  /// Lockstep: drains the rings into the file (every few hundred ticks).
  void pump();
  /// Drains everything, flushes, closes; returns the writer's counters.
  RunLogStats finish();

 private:
  SpscRing<JointStateRecord> joints_;
  SpscRing<ValveCommandRecord> valves_;
  SpscRing<HapticStatusRecord> haptics_;
  SpscRing<SupervisorEventRecord> events_;
  SpscRing<MinimaSetRecord> sets_;
  std::unique_ptr<RunLogWriter> writer_;
  bool threaded_;
  std::uint64_t previous_heartbeat_ = 0;
  std::int64_t seq_joints_ = 0, seq_valves_ = 0, seq_haptics_ = 0, seq_events_ = 0, seq_sets_ = 0;
  bool finished_ = false;
  bool begun_ = false;
};

/// The set record of a lockstep search result adopted at `adopted_tick`.
void toSetRecord(const RecordedSet& set, double period_s, MinimaSetRecord& record) noexcept;

/// Outcome of replayLog().
struct ReplayReport {
  std::filesystem::path log;
  RunOptions options;       ///< rebuilt from the header
  std::string clock;        ///< the recorded run's clock
  std::uint64_t ticks = 0;  ///< ticks replayed
  std::uint64_t sets = 0;   ///< minima sets adopted
  std::uint64_t valve_mismatches = 0;
  std::uint64_t torque_mismatches = 0;
  std::uint64_t force_mismatches = 0;
  std::string first_mismatch;  ///< empty when everything matched
  bool truncated = false;
  std::string warning;                     ///< names the offset of a truncated log
  std::vector<std::string> changed_files;  ///< input files whose SHA-256 differs from the header's
  /// A run over remote I/O (--io lcm): what the node said it serves, from the header's `io_node_*`
  /// parameters, as (joints, period_us, simulated, scripted_user, plant) keys and values; empty
  /// for the other back-ends.
  std::vector<std::pair<std::string, std::string>> io_node;
  [[nodiscard]] bool identical() const noexcept {
    return valve_mismatches == 0 && torque_mismatches == 0 && force_mismatches == 0 && ticks > 0;
  }
};

/// Replays a run log through the same tick (bit for bit). A truncated log replays up to its
/// last complete event (ReplayReport::warning names the offset).
/// @throws RunLogError naming the offset for a corrupt log; core::ConfigError when the header's
///   input files cannot be loaded
[[nodiscard]] ReplayReport replayLog(const std::filesystem::path& log);

/// Lowercase hex SHA-256 of a file's contents.
/// @throws std::runtime_error naming the file if it cannot be read
[[nodiscard]] std::string sha256File(const std::filesystem::path& file);
/// Lowercase hex SHA-256 of bytes.
[[nodiscard]] std::string sha256Hex(std::string_view bytes);

}  // namespace fullarm::hil
