#pragma once
/// @file
/// The fixed-size records the real-time side hands to the log writer and the transports, one
/// per LCM message type (hil/lcm/*.lcm, package fullarm_lcm), their channels, and the
/// conversions between records, LCM messages and haptics::LocalMinimum.
///
/// A record is trivially copyable and holds no pointer, so it can cross an SpscRing or sit in
/// the MinimaExchange; the tick fills it without allocating. The writer thread turns it into
/// its LCM message (which owns std::vectors) and encodes it. Every record carries the
/// producer's sequence number `seq` (a gap in a log shows a drop) and its time `utime_us`.
///
/// Joint-sized arrays hold `num_joints` valid entries in the order of their producer (the I/O
/// device's joints for JointStateRecord and ValveCommandRecord, the arm model's joints for
/// HapticStatusRecord and MinimaSetRecord).

#include <array>
#include <cstdint>
#include <functional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/minima.hpp"
#include "fullarm_lcm/haptic_status_t.hpp"
#include "fullarm_lcm/joint_state_t.hpp"
#include "fullarm_lcm/minima_set_t.hpp"
#include "fullarm_lcm/run_header_t.hpp"
#include "fullarm_lcm/supervisor_event_t.hpp"
#include "fullarm_lcm/valve_command_t.hpp"

namespace fullarm::hil {

/// Joints (and links) a record holds at most: the arm model's bound.
inline constexpr int kMaxRecordJoints = arm::kMaxJoints;
/// Minima a set holds at most (MinimaSetRecord, MinimaExchange).
inline constexpr int kMaxMinimaPerSet = 128;
/// Minima one minima_set_t fragment carries at most: a full fragment (kMaxRecordJoints joint
/// angles) encodes to 1,359 bytes, 1,386 with LCM's short-message header and the channel name:
/// under the 1,400 bytes that fit one UDP datagram on a 1,500-byte MTU (and under LCM's own
/// short-message bound, beyond which LCM would split the message itself). One more minimum
/// (110 bytes) would cross it; a 64-minimum set travels in 6 fragments.
inline constexpr int kMaxMinimaPerFragment = 11;
/// Minima per fragment of the earlier layout (run logs and nodes that split sets in tens): read
/// and reassembled, never written.
inline constexpr int kLegacyMinimaPerFragment = 10;
/// Characters of a supervisor event's message kept in its record (longer text is cut).
inline constexpr int kMaxEventMessageChars = 119;

/// LCM channel names of a run log and of the transports.
namespace channel {
inline constexpr const char* kRunHeader = "FULLARM_RUN_HEADER";
inline constexpr const char* kJointState = "FULLARM_JOINT_STATE";
inline constexpr const char* kValveCommand = "FULLARM_VALVE_COMMAND";
inline constexpr const char* kMinimaSet = "FULLARM_MINIMA_SET";
inline constexpr const char* kHapticStatus = "FULLARM_HAPTIC_STATUS";
inline constexpr const char* kSupervisorEvent = "FULLARM_SUPERVISOR_EVENT";
}  // namespace channel

/// A message or record that cannot be converted: a count beyond its bound, an inconsistent
/// fragment. what() names the field, its value and the bound.
class RecordError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One tick's joint state (joint_state_t).
struct JointStateRecord {
  std::int64_t utime_us = 0;
  std::int64_t seq = 0;
  std::int64_t tick = 0;
  int num_joints = 0;
  std::array<double, kMaxRecordJoints> q_rad{};
  std::array<double, kMaxRecordJoints> tau_measured_nm{};
  std::array<double, kMaxRecordJoints> valve_command_v{};
  std::uint32_t input_flags = 0;  ///< input-check bits (0: every reading valid)
};

/// Valve commands sent (valve_command_t).
struct ValveCommandRecord {
  std::int64_t utime_us = 0;
  std::int64_t seq = 0;
  std::int64_t tick = 0;
  int num_valves = 0;
  std::array<double, kMaxRecordJoints> valve_command_v{};
  bool safe_output = false;  ///< the device's safe outputs, not the law's
};

/// Contact state of one link (link_contact_t).
struct LinkContactStatus {
  std::array<double, 3> force_world_n{};
  double min_distance_m = 0.0;
  double depth_m = 0.0;
  bool in_contact = false;
  bool penetrating = false;
  double contact_duration_s = 0.0;
  double total_penetration_s = 0.0;
};

/// Render mode as logged (haptic_status_t.mode).
enum class LoggedMode : std::int8_t { kFullArm = 0, kHandOnly = 1 };

/// One tick's haptic rendering (haptic_status_t).
struct HapticStatusRecord {
  std::int64_t utime_us = 0;
  std::int64_t seq = 0;
  std::int64_t tick = 0;
  LoggedMode mode = LoggedMode::kFullArm;
  int active_springs = 0;
  int num_minima_tracked = 0;
  std::int64_t minima_set_id = -1;  ///< newest adopted set; -1 before the first
  double contact_scale = 1.0;
  int num_joints = 0;
  std::array<double, kMaxRecordJoints> tau_contact_nm{};
  int num_links = 0;
  std::array<LinkContactStatus, kMaxRecordJoints> links{};
};

/// Severity of a supervisor event (supervisor_event_t.severity).
enum class EventSeverity : std::int8_t { kInfo = 0, kWarning = 1, kFault = 2, kEStop = 3 };

/// A safety-supervisor event (supervisor_event_t). The message is a fixed character buffer so
/// a record can be made on the tick without allocating.
struct SupervisorEventRecord {
  std::int64_t utime_us = 0;
  std::int64_t seq = 0;
  std::int64_t tick = 0;
  int cause_code = 0;
  EventSeverity severity = EventSeverity::kInfo;
  int joint = -1;
  double value = 0.0;                                     ///< NaN if none
  double limit = 0.0;                                     ///< NaN if none
  std::array<char, kMaxEventMessageChars + 1> message{};  ///< NUL-terminated

  /// Copies `text` into `message`, cut at kMaxEventMessageChars. @rt
  void setMessage(std::string_view text) noexcept;
  /// The message as a view. @rt
  [[nodiscard]] std::string_view messageView() const noexcept;
};

/// One minimum of a set (minimum_t): haptics::LocalMinimum in plain fields.
struct MinimumRecord {
  int link = -1;
  int object = -1;
  int tri_link = -1;
  int tri_object = -1;
  std::int8_t feature_link_kind = 0;  ///< haptics::FeatureKind
  int feature_link_index = -1;
  std::int8_t feature_object_kind = 0;
  int feature_object_index = -1;
  std::array<double, 3> p_link_m{};
  std::array<double, 3> p_object_m{};
  double distance_m = 0.0;
  std::array<double, 3> u_world_unit{1.0, 0.0, 0.0};
  double previous_distance_m = 0.0;
};

/// A whole set of minima from the global search, with what it was computed from
/// (minima_set_t, before fragmenting).
struct MinimaSetRecord {
  std::int64_t utime_us = 0;       ///< time it was published or logged
  std::int64_t seq = 0;            ///< producer's sequence number of the record
  std::int64_t set_id = 0;         ///< increases per set
  std::int64_t computed_tick = 0;  ///< tick whose joint angles the search used
  std::int64_t computed_utime_us = 0;
  std::int64_t adopted_tick = -1;  ///< tick that adopted it; -1 if not (yet)
  int num_joints = 0;
  std::array<double, kMaxRecordJoints> q_rad{};  ///< joint angles the search used
  int num_minima = 0;
  int num_minima_dropped = 0;  ///< minima found beyond kMaxMinimaPerSet
  std::array<MinimumRecord, kMaxMinimaPerSet> minima{};
};

static_assert(std::is_trivially_copyable_v<JointStateRecord>);
static_assert(std::is_trivially_copyable_v<ValveCommandRecord>);
static_assert(std::is_trivially_copyable_v<HapticStatusRecord>);
static_assert(std::is_trivially_copyable_v<SupervisorEventRecord>);
static_assert(std::is_trivially_copyable_v<MinimaSetRecord>);

// --- minima ----------------------------------------------------------------------------------

/// The record of a minimum (every field copied bit for bit). @rt
[[nodiscard]] MinimumRecord toMinimumRecord(const haptics::LocalMinimum& minimum) noexcept;
/// The minimum of a record (every field copied bit for bit). @rt
[[nodiscard]] haptics::LocalMinimum toLocalMinimum(const MinimumRecord& record) noexcept;

/// Fills set.minima from `minima`: all of them if they fit, else the kMaxMinimaPerSet closest
/// (ties: the earlier one), in their original order; sets num_minima and num_minima_dropped.
/// The header fields (ids, ticks, q) are left to the caller. @rt
void fillMinima(std::span<const haptics::LocalMinimum> minima, MinimaSetRecord& set) noexcept;

// --- records <-> LCM messages ----------------------------------------------------------------
// toMessage never fails on a record whose counts are within their bounds (counts beyond are
// clamped to the bound). fromMessage validates: a count beyond its record's bound or an array
// whose size disagrees with its count throws RecordError.

[[nodiscard]] fullarm_lcm::joint_state_t toMessage(const JointStateRecord& record);
[[nodiscard]] fullarm_lcm::valve_command_t toMessage(const ValveCommandRecord& record);
[[nodiscard]] fullarm_lcm::haptic_status_t toMessage(const HapticStatusRecord& record);
[[nodiscard]] fullarm_lcm::supervisor_event_t toMessage(const SupervisorEventRecord& record);

[[nodiscard]] JointStateRecord fromMessage(const fullarm_lcm::joint_state_t& message);
[[nodiscard]] ValveCommandRecord fromMessage(const fullarm_lcm::valve_command_t& message);
[[nodiscard]] HapticStatusRecord fromMessage(const fullarm_lcm::haptic_status_t& message);
[[nodiscard]] SupervisorEventRecord fromMessage(const fullarm_lcm::supervisor_event_t& message);

/// Number of fragments a set of `num_minima` minima travels in (>= 1, also for an empty set).
[[nodiscard]] int fragmentCount(int num_minima) noexcept;

/// Fragment `index` (0 .. fragmentCount(set.num_minima) - 1) of a set, with seq = `seq`.
/// @throws RecordError if index is out of range
[[nodiscard]] fullarm_lcm::minima_set_t toFragment(const MinimaSetRecord& set, int index, std::int64_t seq);

/// Checks one fragment on its own: counts within their bounds, fragment_count matching
/// num_minima_total, fragment_index within it, and the fragment carrying exactly its share of
/// the minima, in the current layout (kMaxMinimaPerFragment per fragment) or the earlier one
/// (kLegacyMinimaPerFragment). Returns the layout's minima per fragment.
/// @throws RecordError naming the set, the fragment and the field (and what the current layout
///         expects)
int checkFragment(const fullarm_lcm::minima_set_t& fragment);

/// Reassembles minima sets from their fragments, in the order they arrive. Fragments of one
/// set may come in any order, in either layout (checkFragment) but one layout per set; a
/// fragment of a newer set abandons an incomplete older one (counted), and a fragment of an
/// older set than the one in progress is ignored (counted), unless the producer restarted its
/// numbering: a set id more than kSetRestartJump back, or kSetRestartRun older sets in a row
/// with increasing ids, begin anew (counted in restarts()).
class MinimaSetAssembler {
 public:
  /// A set id this far back is a restarted producer's.
  static constexpr std::int64_t kSetRestartJump = 1000;
  /// This many older sets in a row, with increasing ids, are a restarted producer's.
  static constexpr int kSetRestartRun = 3;

  /// Adds one fragment. Returns true when it completes its set, which is then in `set()`
  /// (valid until the next call).
  /// @throws RecordError for an inconsistent fragment (counts beyond bounds, an index outside
  ///         its count, minima outside the set, a header or a layout that disagrees with the
  ///         set's other fragments)
  bool add(const fullarm_lcm::minima_set_t& fragment);
  /// The set the last successful add() completed.
  [[nodiscard]] const MinimaSetRecord& set() const noexcept { return set_; }
  /// Sets given up incomplete because a newer set began.
  [[nodiscard]] std::uint64_t abandoned() const noexcept { return abandoned_; }
  /// Fragments ignored: of a set older than the one in progress, or repeated.
  [[nodiscard]] std::uint64_t ignored() const noexcept { return ignored_; }
  /// Restarts of the producer's set numbering heard.
  [[nodiscard]] std::uint64_t restarts() const noexcept { return restarts_; }

 private:
  MinimaSetRecord set_{};
  std::int64_t building_id_ = -1;
  bool building_ = false;
  int expected_fragments_ = 0;
  int fragment_size_ = 0;  ///< the set's layout: minima per fragment
  std::array<bool, (kMaxMinimaPerSet + kLegacyMinimaPerFragment - 1) / kLegacyMinimaPerFragment> have_{};
  int have_count_ = 0;
  std::uint64_t abandoned_ = 0;
  std::uint64_t ignored_ = 0;
  std::uint64_t restarts_ = 0;
  std::int64_t older_last_id_ = -1;  ///< the last older set's id seen
  int older_run_ = 0;                ///< older sets in a row, increasing
};

}  // namespace fullarm::hil
