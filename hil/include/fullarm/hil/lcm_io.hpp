#pragma once
/// @file
/// Remote I/O over LCM: the `lcm` IoDevice back-end (the tick's side) and the plant node that
/// serves it from another process or machine (the simulated DTS, or any IoDevice, as an LCM
/// I/O node).
///
/// **Protocol.** Each read() of the LcmIoDevice publishes one io_command_t carrying the command
/// its back-end holds (what write() last put out, after the device's clamping and ramp-in, and
/// whether the amplifiers are enabled) with seq = the read's number, then waits for the
/// io_reading_t with that seq. The node, for each new command: puts it on its device's back-end
/// outputs, reads the back-end's inputs (a simulated plant advances one control period here) and
/// answers. So a remote read is exactly an in-process read of the node's back-end, and a run
/// over LCM gives the in-process run's numbers bit for bit (doubles travel unchanged).
///
/// **Safety.** The tick side keeps the whole IoDevice policy (lifecycle, clamp, ramp-in, safe
/// outputs on fault). A read whose reading does not come within `reply_timeout_s` returns the
/// last reading again; `max_missed_replies` consecutive such reads are a read failure (the link
/// is lost), which faults the device (and the supervisor trips). After one miss, later reads
/// take only a reading that has already arrived, so a lost node does not stall every tick. The node has its own
/// watchdog: when no command has come for `watchdog_timeout_s` it puts out the safe output (null valves, amplifiers
/// disabled) and says so in its heartbeat and its log, until commands resume; a command with enable = false is the safe
/// output too.
///
/// **Description.** The node says what it serves in an io_node_info_t (IoNodeInfo) when it
/// starts and at its heartbeat period: its joints' names in device order, its control period,
/// whether its arm is simulated, whether a scripted user is strapped in, and its plant file.
/// configure() waits for it and refuses a node whose joints or period differ from the device's;
/// the commands that move the arm by themselves check the rest (nodeInfo()).

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/lcm_transport.hpp"
#include "fullarm_lcm/io_command_t.hpp"
#include "fullarm_lcm/io_node_info_t.hpp"
#include "fullarm_lcm/io_reading_t.hpp"

namespace fullarm::hil {

namespace channel {
inline constexpr const char* kIoCommand = "FULLARM_IO_COMMAND";
inline constexpr const char* kIoReading = "FULLARM_IO_READING";
inline constexpr const char* kIoNodeInfo = "FULLARM_IO_NODE_INFO";
}  // namespace channel

/// Characters a joint name of an io_node_info_t has at most.
inline constexpr std::size_t kMaxNodeJointNameChars = 64;
/// Characters the plant field of an io_node_info_t has at most.
inline constexpr std::size_t kMaxNodePlantChars = 512;
/// The longest control period an io_node_info_t may state [us] (1 s).
inline constexpr std::int32_t kMaxNodePeriodUs = 1'000'000;

/// What an I/O node serves, as it says in its io_node_info_t.
struct IoNodeInfo {
  std::vector<std::string> joint_names;  ///< the device's joints, in device order
  /// Control period: one command advances the device this long [us]. In PlantNodeOptions: 0
  /// takes the served device's period.
  std::int32_t period_us = 0;
  bool simulated = true;       ///< a simulated arm (false: real hardware, which moves when commanded)
  bool scripted_user = false;  ///< a scripted user is strapped in: the arm moves by itself
  std::string plant;           ///< the plant file, "<file name> sha256 <hex>" (empty: none)
};

/// An identifier of a description's content (FNV-1a over its encoding with utime and seq zero):
/// the node puts it in every io_reading_t, so a node restarted at the same URL under another
/// description (other joints, period, user or plant file) is told from the one configure()
/// accepted. Never 0.
[[nodiscard]] std::int64_t descriptionId(const IoNodeInfo& info);

/// The message of `info` (utime and seq left for the sender).
[[nodiscard]] fullarm_lcm::io_node_info_t toMessage(const IoNodeInfo& info);
/// The description an io_node_info_t carries.
[[nodiscard]] IoNodeInfo fromMessage(const fullarm_lcm::io_node_info_t& m);
/// "SFE,SAA,HR every 1000 us".
[[nodiscard]] std::string describeJointsAndPeriod(const std::vector<std::string>& joint_names, std::int32_t period_us);

/// Decodes and checks an io_command_t (counts within kMaxIoJoints, array sizes). Never throws.
DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::io_command_t& out) noexcept;
/// Decodes and checks an io_reading_t (counts within kMaxIoJoints, array sizes, a known status
/// code, out-of-range and pressure bits only for the reading's joints). Never throws.
DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::io_reading_t& out) noexcept;
/// Decodes and checks an io_node_info_t: the string lengths before the generated decoder reads
/// them (each joint name 1 to kMaxNodeJointNameChars characters, the plant at most
/// kMaxNodePlantChars, no control characters), counts within kMaxIoJoints, a period in
/// (0, kMaxNodePeriodUs]. Never throws.
DecodeStatus decodeChecked(std::span<const std::uint8_t> bytes, fullarm_lcm::io_node_info_t& out) noexcept;

/// Options of the `lcm` back-end.
struct LcmIoOptions {
  std::string url = kDefaultLcmUrl;  ///< LCM URL shared with the node
  /// The device's joints' names, in device order: configure() refuses a node serving others.
  std::vector<std::string> joint_names;
  /// configure(): how long to wait for the node's heartbeat and description [s].
  double connect_timeout_s = 5.0;
  /// read(): how long to wait for the reading that answers the command [s]. Long, for lockstep
  /// runs, which a loaded machine must not change; a real-time run sets it within the period.
  double reply_timeout_s = 2.0;
  /// Consecutive reads without an answer that mean the link is lost (a device read failure:
  /// the device faults and the supervisor trips). A read before that returns the last reading
  /// again. 20, as libfranka's limit: at 1 kHz 20 ms of a held reading, well inside the plant
  /// node's 100 ms watchdog, and long enough that one late datagram does not stop the arm.
  int max_missed_replies = 20;
};

/// What the `lcm` back-end saw.
struct LcmIoCounters {
  std::uint64_t commands = 0;  ///< io_command_t sent
  std::uint64_t readings = 0;  ///< readings accepted (answering the current command)
  std::uint64_t stale = 0;     ///< readings answering an older command (dropped)
  std::uint64_t rejected = 0;  ///< truncated, wrong-hash or malformed payloads (dropped)
  std::uint64_t timeouts = 0;  ///< reads that got no answer in time
  int consecutive_missed = 0;  ///< reads without an answer since the last answered one
};

/// The `lcm` I/O back-end: the device's inputs and outputs live in an I/O node in another
/// process (LcmPlantNode, `fullarm plant serve`).
class LcmIoDevice final : public IoDevice {
 public:
  /// @throws std::invalid_argument when options.joint_names are not one name per joint
  LcmIoDevice(arm::JointSelection joints, double period_s, const IoSafetyParams& safety, LcmIoOptions options);
  ~LcmIoDevice() override;
  [[nodiscard]] std::string_view name() const noexcept override { return "lcm"; }
  [[nodiscard]] const LcmIoCounters& counters() const noexcept { return counters_; }
  /// What the node said it serves (its joints and period are the device's), or nullptr before
  /// the first configure().
  [[nodiscard]] const IoNodeInfo* nodeInfo() const noexcept { return have_info_ ? &info_ : nullptr; }
  /// hil::descriptionId() of the description configure() accepted (0 before).
  [[nodiscard]] std::int64_t acceptedDescriptionId() const noexcept { return description_id_; }

 private:
  struct Handler;
  /// Opens the LCM URL and waits for the node's heartbeat and description, and checks the
  /// description's joints and period against the device's.
  /// @throws DeviceError when the URL cannot be opened, no node answers or describes itself in
  ///   time, or the node serves other joints or another period (naming the URL, what the node
  ///   serves and what the device expects)
  void onConfigure() override;
  /// Sends the safe output (null valves, enable off) at once, not waiting for a reply, so the
  /// node puts it out without waiting for the next read or its watchdog.
  void onDeactivate() noexcept override;
  /// Sends the held command and waits for its reading (allocates: LCM's receive path).
  core::RtStatus onRead(JointSample& sample) noexcept override;
  core::RtStatus onWrite(const IoVector& valve_v, bool toggle_enable) noexcept override;
  /// Sends the held command and enable under the next sequence number (counted in
  /// counters_.commands); false when LCM could not send it. Throws what encoding throws.
  bool publishHeld();

  LcmIoOptions options_;
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<Handler> handler_;
  IoVector held_v_;
  bool held_enable_ = false;
  JointSample last_sample_;  ///< the last reading received (returned again on a miss)
  bool have_sample_ = false;
  std::int64_t seq_ = 0;
  bool lost_ = false;  ///< the last read got no reply in time: later reads do not wait
  std::vector<std::uint8_t> buffer_;
  LcmIoCounters counters_;
  IoNodeInfo info_;
  bool have_info_ = false;
  std::int64_t description_id_ = 0;
};

/// Options of the plant node.
struct PlantNodeOptions {
  std::string url = kDefaultLcmUrl;
  /// What the node says it serves (describeSessionDevice() for the device of a HilSession). Its joint
  /// names must be as many as the device's joints; its period_us 0 takes the device's period.
  IoNodeInfo info;
  /// No command for this long: safe outputs until commands resume [s].
  double watchdog_timeout_s = 0.1;
  /// Stop serving after this long without a command (also before the first) [s]; <= 0: never.
  double idle_exit_s = 5.0;
  double heartbeat_period_s = 0.05;
  /// Called with each log line as it happens (empty: collected in the result only).
  std::function<void(const std::string&)> on_log;
};

/// What a plant node did.
struct PlantNodeResult {
  std::uint64_t commands = 0;        ///< commands served (one reading each)
  std::uint64_t stale_commands = 0;  ///< commands not newer than the last served (ignored)
  std::uint64_t rejected = 0;        ///< damaged payloads (ignored)
  std::uint64_t watchdog_trips = 0;  ///< times the watchdog put out the safe outputs
  bool safe_at_exit = false;         ///< the outputs were safe when serving stopped
  std::vector<std::string> log;      ///< what happened, in words, with the node's time
};

/// Serves an IoDevice's back-end over LCM (see the file comment for the protocol).
class LcmPlantNode {
 public:
  /// @param device the device whose back-end is served (not owned; configured by serve())
  LcmPlantNode(IoDevice& device, PlantNodeOptions options);
  /// Serves until idle for idle_exit_s or until `stop` returns true (checked every few ms).
  /// @throws DeviceError when the LCM URL cannot be opened; std::invalid_argument when
  ///   options.info names another number of joints than the device's or another period
  PlantNodeResult serve(const std::function<bool()>& stop = {});

 private:
  IoDevice& device_;
  PlantNodeOptions options_;
};

}  // namespace fullarm::hil
