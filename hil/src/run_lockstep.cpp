// The lockstep clock of a run: simulated time, as fast as the machine allows, deterministic
// for a seed. The global search runs synchronously every period_ticks ticks on the tick's joint
// angles and its result is adopted delivery_delay_ticks later; the missed-contact oracle checks
// every tick.

#include <chrono>
#include <cmath>
#include <deque>
#include <utility>

#include "fullarm/arm/kinematics.hpp"
#include "fullarm/hil/lcm_search.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/run_recording.hpp"

namespace fullarm::hil {

namespace {

// Lockstep: a search result waiting for its delivery tick.
struct PendingSet {
  std::uint64_t deliver_tick = 0;
  std::size_t set_index = 0;
};

// The loop's monitor of consecutive overruns.
struct OverrunMonitor {
  int limit = 10;
  int consecutive = 0;
  int max_consecutive = 0;
  std::uint64_t total = 0;
  bool fault = false;
  void add(bool overrun) noexcept {
    if (overrun) {
      ++total;
      ++consecutive;
      max_consecutive = std::max(max_consecutive, consecutive);
      if (consecutive >= limit) fault = true;
    } else {
      consecutive = 0;
    }
  }
};

}  // namespace

RunResult HilSession::runLockstep(const RunHooks& hooks) {
  using Clock = std::chrono::steady_clock;
  RunResult r = startResult();
  const double period = config_.control_period_s;
  const std::uint64_t ticks = static_cast<std::uint64_t>(std::llround(options_.duration_s / period));
  r.telemetry.reserve(ticks);
  r.inputs.reserve(ticks);
  r.user_force_n.reserve(ticks);
  r.hand_W_m.reserve(ticks);

  GlobalSearchRunner search(*model_, *world_, haptics_);
  // The global search in a node of its own: queried at the same ticks, awaited at delivery.
  std::unique_ptr<LcmSearchClient> remote;
  // Lockstep waits long for a set (a loaded machine must not change the run); a silent node
  // costs this once.
  if (!options_.search_url.empty()) remote = std::make_unique<LcmSearchClient>(options_.search_url, 5.0, 2.0);
  std::unique_ptr<MissedContactOracle> oracle;
  if (options_.oracle) oracle = std::make_unique<MissedContactOracle>(*model_, *world_, haptics_.force_threshold_m);
  std::deque<PendingSet> pending;
  TickData data(tick_);
  OverrunMonitor overruns;
  overruns.limit = config_.overrun_limit;
  std::vector<double> compute_s;
  compute_s.reserve(ticks);

  // The log is created first (a run that fails to start leaves an empty file, not an earlier
  // run's log); its header follows the device's configure(), which is where an LCM node's
  // description, recorded in it, is known from.
  std::unique_ptr<RunRecorder> recorder;
  if (!options_.log.empty()) recorder = std::make_unique<RunRecorder>(options_.log, false);
  MinimaSetRecord set_record;

  device_->configure();
  if (recorder) recorder->begin(*this, options_.command_line);

  device_->activate();
  JointSample sample;
  IoVector valve;
  TickTelemetry telemetry;
  std::uint64_t heartbeat = 0;
  arm::ArmData hand_fk(*model_);
  const auto loop_start = Clock::now();
  for (std::uint64_t k = 1; k <= ticks; ++k) {
    const auto t0 = Clock::now();
    const core::RtStatus read_status = device_->read(sample);
    const auto t1 = Clock::now();

    SupervisorRequests requests;
    // The supervising side beats every heartbeat_period_s of simulated time.
    heartbeat = static_cast<std::uint64_t>(std::floor(static_cast<double>(k) * period / config_.heartbeat_period_s));
    requests.heartbeat = heartbeat;
    requests.heartbeat_enabled = true;
    requests.overrun_fault = overruns.fault;
    if (hooks.before_tick) hooks.before_tick(k, sample, requests);

    MinimaDelivery delivery;
    const MinimaDelivery* delivered = nullptr;
    RecordedTick recorded{sample, read_status, requests, -1};
    if (!pending.empty() && pending.front().deliver_tick == k) {
      RecordedSet& set = r.sets[pending.front().set_index];
      pending.pop_front();
      // A remote set that does not come in time is not adopted (the old minima go stale).
      if (!remote || remote->await(set.id, set.query_tick, set.minima, set.found)) {
        set.adopted_tick = static_cast<std::int64_t>(k);
        delivery.set_id = set.id;
        delivery.minima = set.minima;
        delivery.query_q_rad = set.query_q_rad;
        delivered = &delivery;
        recorded.adopted_set = set.id;
        if (recorder) {
          toSetRecord(set, period, set_record);
          recorder->recordAdoptedSet(set_record);
        }
      }
    }
    r.inputs.push_back(recorded);

    TickInputs in;
    in.sample = &sample;
    in.device_status = read_status;
    in.minima = delivered;
    in.requests = requests;
    stepTick(tick_, data, in, valve, telemetry);
    const auto t2 = Clock::now();
    if (hooks.after_tick) {
      hooks.after_tick(k, valve);
      // The output limits again, on what reaches the device.
      data.supervisor.num_events = 0;
      supervisorLimitOutputs(tick_.supervisor, data.supervisor, valve);
      for (int e = 0; e < data.supervisor.num_events && telemetry.num_events < kMaxEventsPerTick; ++e) {
        telemetry.events[static_cast<std::size_t>(telemetry.num_events++)] =
            data.supervisor.events[static_cast<std::size_t>(e)];
      }
      telemetry.supervisor_state = data.supervisor.state;
      telemetry.trip_cause = data.supervisor.trip_cause;
      for (int j = 0; j < valve.size(); ++j) telemetry.valve_v[static_cast<std::size_t>(j)] = valve[j];
    }
    if (data.supervisor.state == SupervisorState::kTripped && device_->state() != IoState::kFault) {
      device_->fault(supervisorCauseName(data.supervisor.trip_cause));
    }
    (void)device_->write(valve);
    const auto t3 = Clock::now();
    r.telemetry.push_back(telemetry);
    if (recorder) {
      recorder->recordTick(r.inputs.back(), telemetry, device_->appliedCommand(), device_->state() != IoState::kActive,
                           static_cast<std::int64_t>(std::llround(telemetry.t_s * 1e6)));
      if (k % 256 == 0) recorder->pump();
    }
    if (arm_) {
      arm::computeForwardKinematics(*model_, hand_fk, arm_->trueConfiguration());
      r.hand_W_m.push_back(hand_fk.X_WT.translation());
      r.user_force_n.push_back(user_ ? user_->lastForce().norm() : 0.0);
    }

    // The global search, synchronous every period_ticks, delivered delivery_delay_ticks later.
    double search_s = 0.0;
    if (k % static_cast<std::uint64_t>(config_.global_period_ticks) == 0 &&
        !(hooks.search_stalled && hooks.search_stalled(k))) {
      RecordedSet set;
      set.id = static_cast<std::int64_t>(r.sets.size()) + 1;
      set.query_tick = k;
      set.query_q_rad.assign(data.q.data(), data.q.data() + data.q.size());
      if (remote) {
        remote->query(set.id, k, data.q);
      } else {
        set.found = search.run(data.q, set.minima);
        search_s = search.lastSeconds();
      }
      r.sets.push_back(std::move(set));
      pending.push_back({k + static_cast<std::uint64_t>(config_.delivery_delay_ticks), r.sets.size() - 1});
      ++r.timing.searches;
    }
    const auto t4 = Clock::now();
    if (oracle) {
      oracle->check(
          k, data.q,
          std::span<const haptics::LocalMinimum>(data.tracked.data(), static_cast<std::size_t>(data.num_tracked)));
    }
    const auto t5 = Clock::now();

    const double tick_compute = std::chrono::duration<double>((t1 - t0) + (t3 - t2) + (t2 - t1)).count();
    compute_s.push_back(tick_compute);
    r.timing.plant_s += std::chrono::duration<double>((t1 - t0) + (t3 - t2)).count();
    r.timing.tick_s += std::chrono::duration<double>(t2 - t1).count();
    r.timing.search_s += search_s;
    r.timing.oracle_s += std::chrono::duration<double>(t5 - t4).count();
    // Lockstep has no deadline: an overrun is only what a test injects.
    const double extra = hooks.extra_compute_s ? hooks.extra_compute_s(k) : 0.0;
    overruns.add(extra > period);
  }
  r.timing.wall_s = std::chrono::duration<double>(Clock::now() - loop_start).count();
  device_->deactivate();
  if (recorder) {
    const RunLogStats stats = recorder->finish();
    r.log_events = stats.events_written;
    r.log_records_dropped = stats.records_dropped;
  }
  r.timing.ticks = ticks;
  r.timing.simulated_s = static_cast<double>(ticks) * period;
  r.timing.compute = percentiles(compute_s);
  r.timing.compute_samples_s = std::move(compute_s);
  r.timing.overruns = overruns.total;
  r.timing.max_consecutive_overruns = overruns.max_consecutive;
  if (oracle) {
    r.oracle_ran = true;
    r.oracle_ticks = oracle->checkedTicks();
    r.missed_contact_ticks = oracle->missedTicks();
    r.missed_contacts = oracle->missed();
    r.link_min_distance_m = oracle->minDistance();
    r.link_max_penetration_m = oracle->maxPenetration();
    for (const std::uint64_t n : oracle->penetrationTicks())
      r.link_penetration_s.push_back(static_cast<double>(n) * period);
  }
  finishResult(r);
  return r;
}

}  // namespace fullarm::hil
