#pragma once
/// @file
/// A haptic run (`fullarm run`): the scene, the arm, an I/O device, the scripted user, the tick
/// and the global search beside it, driven by one of two clocks:
///  - lockstep: simulated time, as fast as the machine allows, deterministic for a seed (tests,
///    studies, replays). The global search runs synchronously every `period_ticks` ticks and its
///    result is adopted `delivery_delay_ticks` later, so a lockstep run still shows the paper's
///    latency hazard;
///  - realtime: the tick on a 1 kHz absolute-time clock (clock_nanosleep), the global search in
///    its own thread (run_realtime.cpp).
/// Every input of every tick is recorded, so replay() feeds them through a fresh tick and
/// reproduces every force, torque and valve command bit for bit.

#include <Eigen/Core>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/fake_daq.hpp"
#include "fullarm/hil/global_search.hpp"
#include "fullarm/hil/hil_config.hpp"
#include "fullarm/hil/io_backend.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/scripted_user.hpp"
#include "fullarm/hil/simulated_arm.hpp"
#include "fullarm/hil/tick.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::hil {

/// Which clock drives the run.
enum class ClockKind { kLockstep, kRealtime };

[[nodiscard]] const char* clockKindName(ClockKind clock) noexcept;

/// What a run is made of. Empty paths take the shipped defaults.
struct RunOptions {
  IoKind io = IoKind::kSim;
  haptics::RenderMode mode = haptics::RenderMode::kFullArm;
  ClockKind clock = ClockKind::kLockstep;
  double duration_s = 10.0;
  std::filesystem::path scene;  ///< default scenes/valve_wall.yaml
  std::filesystem::path user;   ///< default config/user_reach_valve.yaml
  /// false: the simulated arm moves with nobody strapped in (no scripted user; `user` unread).
  bool scripted_user = true;
  std::filesystem::path arm_config, plant_config, gains_config, haptics_config, hil_config, daq_config;
  std::string start_posture = "ready";  ///< a posture of the scene
  std::uint64_t seed = 1;               ///< the plant's sensor noise
  /// Lockstep: run the missed-contact oracle on every tick.
  bool oracle = true;
  /// Overrides of the loop configuration.
  std::optional<int> delivery_delay_ticks;
  std::optional<int> global_period_ticks;
  /// fakedaq: keep the fake board's state in this file (empty: in memory), so that another
  /// process can look at the board after this one died.
  std::filesystem::path fakedaq_state_file;
  /// sim: read and write through the channel map's converters and calibrations (those of the
  /// fake DAQ), for a bit-for-bit comparison of the two back-ends.
  bool sim_uses_daq_converters = false;
  /// lcm: the LCM URL shared with the plant node (empty: kDefaultLcmUrl, which stays on this
  /// machine).
  std::string lcm_url;
  /// The global search runs in a global node (`fullarm global`, lcm_search.hpp) reached over
  /// this LCM URL (empty: in this process): in lockstep each query waits for its set
  /// (LcmSearchClient), in real time the tick's joint angles go out live and sets are adopted
  /// as they arrive (LcmLiveSearchClient).
  std::string search_url;
  /// The run's LCM log (empty: none) and the command line its header records.
  std::filesystem::path log;
  std::string command_line;
};

/// Hooks of the tests' fault injection, called on the loop's thread (empty in normal runs).
struct RunHooks {
  /// Before the tick: may change the reading and the requests (E-stop, reset, heartbeat).
  std::function<void(std::uint64_t tick, JointSample& sample, SupervisorRequests& requests)> before_tick;
  /// After the tick, before the write: may change the valve commands; the supervisor's output
  /// limits run again on them before they reach the device.
  std::function<void(std::uint64_t tick, IoVector& valve_v)> after_tick;
  /// True: the global search does not run at this tick (a stalled search).
  std::function<bool(std::uint64_t tick)> search_stalled;
  /// Lockstep: compute time added to the tick [s] (an overrun when above the period);
  /// real time: the tick busy-waits this long.
  std::function<double(std::uint64_t tick)> extra_compute_s;
};

/// p50 / p99 / max of a timing series [s].
struct Percentiles {
  double p50_s = 0.0;
  double p99_s = 0.0;
  double max_s = 0.0;
};

/// Timing of a run.
struct RunTiming {
  std::uint64_t ticks = 0;
  double wall_s = 0.0;                          ///< wall time of the loop
  double simulated_s = 0.0;                     ///< ticks x period
  Percentiles compute;                          ///< per tick: read, tick, write (and the lockstep search)
  Percentiles period_jitter;                    ///< real time: |wake-up - deadline|
  std::vector<double> compute_samples_s;        ///< per tick: the samples of `compute`
  std::vector<double> period_jitter_samples_s;  ///< real time, per tick: the samples of `period_jitter`
  std::uint64_t overruns = 0;                   ///< ticks that ended after the next deadline
  int max_consecutive_overruns = 0;
  // Lockstep breakdown of the wall time [s].
  double plant_s = 0.0;   ///< device reads and writes (the simulated plant)
  double tick_s = 0.0;    ///< stepTick
  double search_s = 0.0;  ///< the global search
  double oracle_s = 0.0;  ///< the missed-contact oracle
  std::uint64_t searches = 0;
  /// Real time: how the threads were scheduled (SCHED_FIFO, mlockall, pinning, or why not).
  std::vector<std::string> realtime_notes;
  bool realtime_scheduling = false;  ///< SCHED_FIFO granted to the tick thread
};

/// The inputs of one tick, as recorded.
struct RecordedTick {
  JointSample sample;
  core::RtStatus device_status;
  SupervisorRequests requests;
  std::int64_t adopted_set = -1;  ///< id of the set adopted at this tick, -1 for none
};

/// A minima set of the run.
struct RecordedSet {
  std::int64_t id = 0;
  std::uint64_t query_tick = 0;    ///< tick whose joint angles the search used
  std::int64_t adopted_tick = -1;  ///< tick that adopted it (-1: never)
  std::vector<double> query_q_rad;
  std::vector<haptics::LocalMinimum> minima;
  int found = 0;  ///< minima the search found before the tick's capacity
};

/// Outcome of a run.
struct RunResult {
  RunOptions options;
  std::string io_name;
  std::vector<std::string> joint_names;  ///< device joints
  std::vector<std::string> link_names;   ///< model links
  std::vector<TickTelemetry> telemetry;  ///< one per tick
  std::vector<RecordedTick> inputs;      ///< one per tick
  std::vector<RecordedSet> sets;
  std::vector<SupervisorEvent> events;
  RunTiming timing;
  bool tripped = false;
  SupervisorCause trip_cause = SupervisorCause::kNone;
  // Missed-contact oracle (lockstep).
  bool oracle_ran = false;
  std::uint64_t oracle_ticks = 0;
  std::uint64_t missed_contact_ticks = 0;
  std::vector<MissedContact> missed_contacts;
  std::vector<double> link_min_distance_m;  ///< exact, per link, over the run
  std::vector<double> link_max_penetration_m;
  std::vector<double> link_penetration_s;
  std::uint64_t sweep_exceeded_ticks = 0;  ///< ticks where a link swept beyond L - d_f
  // The user's task.
  double hand_to_target_m = 0.0;  ///< final hand point to the path's last via point
  double max_user_force_n = 0.0;
  std::vector<double> user_force_n;       ///< per tick
  std::vector<Eigen::Vector3d> hand_W_m;  ///< true hand point per tick (simulated back-ends)
  // The LCM log.
  std::uint64_t log_events = 0;
  std::uint64_t log_records_dropped = 0;
  std::string log_error;
};

/// Everything a run is built from, loaded and checked.
/// @throws core::ConfigError / std::runtime_error for bad files or a missing device
class HilSession {
 public:
  /// @param build_device false: only the tick's model (for replay), no device or plant
  explicit HilSession(const RunOptions& options, bool build_device = true);
  ~HilSession();
  HilSession(const HilSession&) = delete;
  HilSession& operator=(const HilSession&) = delete;

  /// Runs once (a session runs at most once: the device and plant are not rewound).
  RunResult run(const RunHooks& hooks = {});

  /// Feeds the recorded inputs of `recorded` through a fresh tick of this run's model and
  /// returns its telemetry (equal, bit for bit, to the recorded run's).
  [[nodiscard]] std::vector<TickTelemetry> replay(const RunResult& recorded) const;

  [[nodiscard]] const RunOptions& options() const noexcept { return options_; }
  [[nodiscard]] const arm::ArmModel& model() const noexcept { return *model_; }
  [[nodiscard]] const haptics::Scene& scene() const noexcept { return *scene_; }
  [[nodiscard]] const haptics::CollisionWorld& world() const noexcept { return *world_; }
  [[nodiscard]] const TickModel& tickModel() const noexcept { return tick_; }
  [[nodiscard]] const HilConfig& config() const noexcept { return config_; }
  [[nodiscard]] const haptics::HapticsParams& hapticsParams() const noexcept { return haptics_; }
  [[nodiscard]] IoDevice& device() noexcept { return *device_; }
  /// The device, or nullptr for a session built without one (replay).
  [[nodiscard]] const IoDevice* deviceOrNull() const noexcept { return device_; }
  /// The simulated arm behind sim and fakedaq (nullptr for comedi).
  [[nodiscard]] SimulatedArm* simulatedArm() noexcept { return arm_; }
  [[nodiscard]] const ScriptedUser* user() const noexcept { return user_.get(); }

 private:
  RunResult runLockstep(const RunHooks& hooks);
  RunResult runRealtime(const RunHooks& hooks);
  RunResult startResult() const;
  void finishResult(RunResult& result) const;

  RunOptions options_;
  std::unique_ptr<arm::ArmModel> model_;
  std::unique_ptr<haptics::Scene> scene_;
  std::unique_ptr<haptics::CollisionWorld> world_;
  HilConfig config_;
  haptics::HapticsParams haptics_;
  controllers::GainsConfig gains_;
  plant::PlantConfig plant_;
  DaqConfig daq_;
  Eigen::VectorXd posture_;
  std::unique_ptr<ScriptedUser> user_;
  std::unique_ptr<IoBackend> backend_;
  SimulatedArm* arm_ = nullptr;  // the backend's (sim, fakedaq)
  IoDevice* device_ = nullptr;   // the backend's
  TickModel tick_;
  bool ran_ = false;
};

/// Loads a session and runs it.
[[nodiscard]] RunResult runHil(const RunOptions& options, const RunHooks& hooks = {});

/// The percentiles of a series (sorted copy).
[[nodiscard]] Percentiles percentiles(std::vector<double> values);

}  // namespace fullarm::hil
