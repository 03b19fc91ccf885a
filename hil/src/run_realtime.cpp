// The real-time clock of a run: the tick on a 1 kHz absolute-time clock (clock_nanosleep on
// CLOCK_MONOTONIC, next += period, missed periods skipped rather than burst), SCHED_FIFO,
// mlockall and CPU pinning when the system permits them (a note says so, or why not), the
// global search in its own thread handing sets over through the MinimaExchange, the latest joint
// angles going the other way through an SpscRing (or, with the global node over LCM, the joint
// angles out through the publisher thread and the node's sets in through a receiving thread),
// the heartbeat beaten by the thread that waits for the run, and SIGINT / SIGTERM as an E-stop.

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstring>
#include <string>
#include <thread>
#include <utility>

#include "fullarm/arm/kinematics.hpp"
#include "fullarm/hil/lcm_search.hpp"
#include "fullarm/hil/log_records.hpp"
#include "fullarm/hil/minima_exchange.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/run_recording.hpp"
#include "fullarm/hil/spsc_ring.hpp"

namespace fullarm::hil {
namespace {

std::atomic<bool> g_stop_signal{false};

extern "C" void onStopSignal(int /*signal*/) {
  g_stop_signal.store(true, std::memory_order_relaxed);
}

constexpr std::int64_t kNsPerS = 1'000'000'000;

// A sanitizer reserves terabytes of shadow memory: locking every mapped page is not possible
// there (and would not be real time anyway).
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
constexpr bool kSanitizerBuild = true;
#else
constexpr bool kSanitizerBuild = false;
#endif

timespec toTimespec(std::int64_t ns) noexcept {
  return {static_cast<time_t>(ns / kNsPerS), static_cast<long>(ns % kNsPerS)};
}

std::int64_t nowNs() noexcept {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * kNsPerS + t.tv_nsec;
}

void sleepUntil(std::int64_t ns) noexcept {
  const timespec t = toTimespec(ns);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &t, nullptr) == EINTR) {
  }
}

/// Real-time scheduling of the calling thread; returns a note for the report.
std::string makeRealtime(int priority, int cpu, bool& fifo_granted) {
  std::string note;
  sched_param param{};
  param.sched_priority = priority;
  const int fifo = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
  fifo_granted = fifo == 0;
  note += fifo == 0 ? "SCHED_FIFO priority " + std::to_string(priority)
                    : "WARNING: SCHED_FIFO refused (" + std::string(std::strerror(fifo)) +
                          "): the thread runs under the normal scheduler, so its timing is not real-time";
  if (cpu >= 0) {
    const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
    if (cpu < cpus) {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(static_cast<unsigned>(cpu), &set);
      const int pin = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
      note += pin == 0 ? ", pinned to CPU " + std::to_string(cpu)
                       : ", WARNING: pinning to CPU " + std::to_string(cpu) + " refused (" + std::strerror(pin) + ")";
    } else {
      note +=
          ", WARNING: CPU " + std::to_string(cpu) + " does not exist (" + std::to_string(cpus) + " online): not pinned";
    }
  }
  return note;
}

struct ScopedSignals {
  struct sigaction old_int {
  }, old_term{};
  ScopedSignals() {
    g_stop_signal.store(false);
    struct sigaction sa {};
    sa.sa_handler = onStopSignal;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int);
    sigaction(SIGTERM, &sa, &old_term);
  }
  ~ScopedSignals() {
    sigaction(SIGINT, &old_int, nullptr);
    sigaction(SIGTERM, &old_term, nullptr);
  }
};

}  // namespace

RunResult HilSession::runRealtime(const RunHooks& hooks) {
  RunResult r = startResult();
  const double period = config_.control_period_s;
  const std::int64_t period_ns = std::llround(period * 1e9);
  const std::uint64_t ticks = static_cast<std::uint64_t>(std::llround(options_.duration_s / period));
  // Everything the tick thread writes is allocated here.
  r.telemetry.resize(ticks);
  r.inputs.resize(ticks);
  r.user_force_n.resize(arm_ ? ticks : 0);
  r.hand_W_m.resize(arm_ ? ticks : 0);
  std::vector<double> compute_s(ticks, 0.0);
  std::vector<double> jitter_s(ticks, 0.0);

  bool locked = false;
  if (kSanitizerBuild) {
    r.timing.realtime_notes.push_back("WARNING: memory not locked: a sanitizer build cannot lock its shadow memory");
  } else if (mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    locked = true;
    r.timing.realtime_notes.push_back("memory locked (mlockall)");
  } else {
    r.timing.realtime_notes.push_back(std::string("WARNING: mlockall refused (") + std::strerror(errno) +
                                      "): page faults may delay ticks");
  }

  MinimaExchange exchange;
  SpscRing<JointStateRecord> angles(256);
  std::atomic<bool> stop_search{false};
  std::atomic<std::uint64_t> heartbeat{0};
  std::vector<RecordedSet> sets;  // the search thread's, read after join
  std::string search_note;
  double search_s = 0.0;
  std::uint64_t searches = 0;

  // The log is created first (a run that fails to start leaves an empty file, not an earlier
  // run's log); then the device: a missing board ends the run before any thread starts, and an
  // LCM node's description, which the log's header records, is known from its configure().
  std::unique_ptr<RunRecorder> recorder;
  if (!options_.log.empty()) recorder = std::make_unique<RunRecorder>(options_.log, true);
  device_->configure();
  if (recorder) recorder->begin(*this, options_.command_line);
  // The global node over LCM, when the search is remote: no node is an error before any thread
  // starts.
  std::unique_ptr<LcmLiveSearchClient> remote;
  if (!options_.search_url.empty()) {
    remote = std::make_unique<LcmLiveSearchClient>(options_.search_url, 5.0, config_.heartbeat_period_s);
  }
  device_->activate();

  // Sets from the global node over LCM: each whole set that arrives is handed to the tick. Its
  // heartbeat is watched here: none for peer_heartbeat_timeout_s is communication loss.
  std::atomic<bool> peer_lost{false};
  const auto receive_remote_sets = [&] {
    search_note = "global search: the global node over LCM at " + options_.search_url +
                  " (live joint states every global period, sets adopted as they arrive)";
    const auto timeout = std::chrono::duration<double>(config_.supervisor.peer_heartbeat_timeout_s);
    std::uint64_t beats = remote->receiver().heartbeatsFrom(NodeKind::kGlobal);
    auto last_beat = std::chrono::steady_clock::now();
    while (!stop_search.load(std::memory_order_relaxed)) {
      const MinimaSetRecord* s = remote->waitForSet(0.005);
      const auto now = std::chrono::steady_clock::now();
      if (remote->receiver().heartbeatsFrom(NodeKind::kGlobal) != beats) {
        beats = remote->receiver().heartbeatsFrom(NodeKind::kGlobal);
        last_beat = now;
      } else if (now - last_beat > timeout) {
        peer_lost.store(true, std::memory_order_relaxed);
      }
      if (s == nullptr) continue;
      if (hooks.search_stalled && hooks.search_stalled(static_cast<std::uint64_t>(s->computed_tick))) continue;
      RecordedSet set;
      set.id = static_cast<std::int64_t>(sets.size()) + 1;
      set.query_tick = static_cast<std::uint64_t>(s->computed_tick);
      set.query_q_rad.assign(s->q_rad.begin(), s->q_rad.begin() + s->num_joints);
      set.minima.reserve(static_cast<std::size_t>(s->num_minima));
      for (int i = 0; i < s->num_minima; ++i) {
        set.minima.push_back(toLocalMinimum(s->minima[static_cast<std::size_t>(i)]));
      }
      set.found = s->num_minima + s->num_minima_dropped;
      ++searches;
      MinimaSetRecord& slot = exchange.writeSlot();
      slot = *s;
      slot.set_id = set.id;  // the run's own numbering, as the in-process search's
      slot.computed_utime_us = std::llround(static_cast<double>(s->computed_tick) * period * 1e6);
      slot.adopted_tick = -1;
      sets.push_back(std::move(set));
      exchange.publish();
    }
  };

  // The global search: every global period, on the newest joint angles the tick sent.
  std::thread search_thread([&] {
    if (remote) {
      receive_remote_sets();
      return;
    }
    bool fifo = false;
    search_note = "global search thread: " + makeRealtime(config_.search_priority, -1, fifo);
    GlobalSearchRunner runner(*model_, *world_, haptics_);
    Eigen::VectorXd q = posture_;
    bool have_q = false;
    std::int64_t query_tick = 0;
    const std::int64_t global_ns = period_ns * config_.global_period_ticks;
    std::int64_t next = nowNs() + global_ns;
    while (!stop_search.load(std::memory_order_relaxed)) {
      sleepUntil(next);
      next += global_ns;
      angles.consumeAll([&](const JointStateRecord& rec) {
        for (int k = 0; k < rec.num_joints; ++k)
          q[tick_.device_joints.modelIndex(k)] = rec.q_rad[static_cast<std::size_t>(k)];
        query_tick = rec.tick;
        have_q = true;
      });
      if (!have_q) continue;
      if (hooks.search_stalled && hooks.search_stalled(static_cast<std::uint64_t>(query_tick))) continue;
      RecordedSet set;
      set.id = static_cast<std::int64_t>(sets.size()) + 1;
      set.query_tick = static_cast<std::uint64_t>(query_tick);
      set.query_q_rad.assign(q.data(), q.data() + q.size());
      set.found = runner.run(q, set.minima);
      search_s += runner.lastSeconds();
      ++searches;
      MinimaSetRecord& slot = exchange.writeSlot();
      slot.set_id = set.id;
      slot.computed_tick = query_tick;
      slot.computed_utime_us = std::llround(static_cast<double>(query_tick) * period * 1e6);
      slot.adopted_tick = -1;
      slot.num_joints = static_cast<int>(q.size());
      for (int j = 0; j < slot.num_joints; ++j) slot.q_rad[static_cast<std::size_t>(j)] = q[j];
      fillMinima(set.minima, slot);
      slot.num_minima_dropped += set.found - static_cast<int>(set.minima.size());
      sets.push_back(std::move(set));
      exchange.publish();
    }
  });

  ScopedSignals signals;
  std::atomic<bool> tick_done{false};
  std::string tick_note;
  bool tick_fifo = false;
  std::uint64_t overruns = 0;
  int consecutive = 0;
  int max_consecutive = 0;
  std::uint64_t ticks_run = 0;
  double wall_s = 0.0;

  std::thread tick_thread([&] {
    tick_note = "tick thread: " + makeRealtime(config_.realtime_priority, config_.tick_cpu, tick_fifo);
    TickData data(tick_);
    JointSample sample;
    IoVector valve;
    std::vector<haptics::LocalMinimum> adopted(static_cast<std::size_t>(kMaxTrackedMinima));
    std::vector<double> adopted_q(static_cast<std::size_t>(model_->numJoints()));
    MinimaSetRecord adopted_record;
    arm::ArmData hand_fk(*model_);
    std::vector<double> live_q(posture_.data(), posture_.data() + posture_.size());
    bool overrun_fault = false;
    std::uint64_t stop_at = ticks;
    const std::int64_t start = nowNs() + period_ns;
    std::int64_t deadline = start;
    for (std::uint64_t k = 1; k <= stop_at; ++k) {
      sleepUntil(deadline);
      const std::int64_t wake = nowNs();
      jitter_s[k - 1] = static_cast<double>(std::llabs(wake - deadline)) * 1e-9;
      RecordedTick& rec = r.inputs[k - 1];
      rec.device_status = device_->read(sample);
      rec.sample = sample;
      SupervisorRequests& requests = rec.requests;
      requests = {};
      requests.heartbeat = heartbeat.load(std::memory_order_relaxed);
      requests.heartbeat_enabled = true;
      requests.estop_signal = g_stop_signal.load(std::memory_order_relaxed);
      requests.overrun_fault = overrun_fault;
      requests.peer_heartbeat_lost = peer_lost.load(std::memory_order_relaxed);
      if (hooks.before_tick) hooks.before_tick(k, rec.sample, requests);
      MinimaDelivery delivery;
      TickInputs in;
      in.sample = &rec.sample;
      in.device_status = rec.device_status;
      rec.adopted_set = -1;
      if (const MinimaSetRecord* set = exchange.takeNewest()) {
        const std::size_t n = static_cast<std::size_t>(set->num_minima);
        for (std::size_t i = 0; i < n; ++i) adopted[i] = toLocalMinimum(set->minima[i]);
        for (int j = 0; j < set->num_joints && j < model_->numJoints(); ++j) {
          adopted_q[static_cast<std::size_t>(j)] = set->q_rad[static_cast<std::size_t>(j)];
        }
        delivery.set_id = set->set_id;
        delivery.minima = std::span<const haptics::LocalMinimum>(adopted.data(), n);
        delivery.query_q_rad = adopted_q;
        in.minima = &delivery;
        rec.adopted_set = set->set_id;
        if (recorder) {
          adopted_record = *set;
          adopted_record.adopted_tick = static_cast<std::int64_t>(k);
          adopted_record.utime_us = std::llround(static_cast<double>(k) * period * 1e6);
          recorder->recordAdoptedSet(adopted_record);
        }
      }
      in.requests = requests;
      TickTelemetry& telemetry = r.telemetry[k - 1];
      stepTick(tick_, data, in, valve, telemetry);
      if (hooks.after_tick) {
        hooks.after_tick(k, valve);
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
      // The search's next query uses these angles.
      if (remote) {
        // Live to the global node every global period: the model configuration (the posture
        // with the device's joints read), through the publisher thread's ring.
        if (k % static_cast<std::uint64_t>(config_.global_period_ticks) == 0) {
          for (int j = 0; j < sample.q_rad.size(); ++j) {
            live_q[static_cast<std::size_t>(tick_.device_joints.modelIndex(j))] = sample.q_rad[j];
          }
          (void)remote->pushConfiguration(static_cast<std::int64_t>(k), live_q.data(), static_cast<int>(live_q.size()));
        }
        remote->setNodeState(static_cast<std::int64_t>(k), device_->state() != IoState::kActive);
      } else {
        angles.tryPushWith([&](JointStateRecord& a) {
          a.tick = static_cast<std::int64_t>(k);
          a.num_joints = static_cast<int>(sample.q_rad.size());
          for (int j = 0; j < sample.q_rad.size(); ++j) a.q_rad[static_cast<std::size_t>(j)] = sample.q_rad[j];
        });
      }
      if (recorder) {
        recorder->recordTick(rec, telemetry, device_->appliedCommand(), device_->state() != IoState::kActive,
                             (wake - start) / 1000);
      }
      if (arm_) {
        arm::computeForwardKinematics(*model_, hand_fk, arm_->trueConfiguration());
        r.hand_W_m[k - 1] = hand_fk.X_WT.translation();
        r.user_force_n[k - 1] = user_ ? user_->lastForce().norm() : 0.0;
      }
      if (hooks.extra_compute_s) {
        const std::int64_t until = nowNs() + std::llround(hooks.extra_compute_s(k) * 1e9);
        while (nowNs() < until) {
        }
      }
      const std::int64_t end = nowNs();
      compute_s[k - 1] = static_cast<double>(end - wake) * 1e-9;
      ticks_run = k;
      // An overrun ends after the next deadline; the periods it covered are skipped.
      deadline += period_ns;
      if (end > deadline) {
        ++overruns;
        ++consecutive;
        max_consecutive = std::max(max_consecutive, consecutive);
        if (consecutive >= config_.overrun_limit) overrun_fault = true;
        deadline += ((end - deadline) / period_ns + 1) * period_ns;
      } else {
        consecutive = 0;
      }
      // A stop signal ends the run 0.1 s after the E-stop, with the valves at null meanwhile.
      if (requests.estop_signal && stop_at == ticks)
        stop_at = std::min(ticks, k + static_cast<std::uint64_t>(0.1 / period));
    }
    wall_s = static_cast<double>(nowNs() - start) * 1e-9;
    tick_done.store(true);
  });
  // This thread is the supervising side: it beats the heartbeat until the tick thread is done.
  const auto beat = std::chrono::duration<double>(config_.heartbeat_period_s);
  while (!tick_done.load()) {
    std::this_thread::sleep_for(beat);
    heartbeat.fetch_add(1, std::memory_order_relaxed);
  }
  tick_thread.join();
  stop_search.store(true);
  search_thread.join();
  if (remote) remote->stop();
  device_->deactivate();
  if (locked) munlockall();

  r.telemetry.resize(ticks_run);
  r.inputs.resize(ticks_run);
  compute_s.resize(ticks_run);
  jitter_s.resize(ticks_run);
  if (arm_) {
    r.hand_W_m.resize(ticks_run);
    r.user_force_n.resize(ticks_run);
  }
  r.sets = std::move(sets);
  for (std::size_t k = 0; k < r.inputs.size(); ++k) {
    if (r.inputs[k].adopted_set > 0) {
      r.sets[static_cast<std::size_t>(r.inputs[k].adopted_set - 1)].adopted_tick = static_cast<std::int64_t>(k + 1);
    }
  }
  if (recorder) {
    const RunLogStats stats = recorder->finish();
    r.log_events = stats.events_written;
    r.log_records_dropped = stats.records_dropped;
    r.log_error = stats.write_errors > 0 || stats.encode_errors > 0 ? "the log writer reported errors" : "";
  }
  r.timing.realtime_notes.push_back(tick_note);
  r.timing.realtime_notes.push_back(search_note);
  r.timing.realtime_scheduling = tick_fifo;
  r.timing.ticks = ticks_run;
  r.timing.wall_s = wall_s;
  r.timing.simulated_s = static_cast<double>(ticks_run) * period;
  r.timing.compute = percentiles(compute_s);
  r.timing.period_jitter = percentiles(jitter_s);
  r.timing.compute_samples_s = std::move(compute_s);
  r.timing.period_jitter_samples_s = std::move(jitter_s);
  r.timing.overruns = overruns;
  r.timing.max_consecutive_overruns = max_consecutive;
  r.timing.search_s = search_s;
  r.timing.searches = searches;
  finishResult(r);
  return r;
}

}  // namespace fullarm::hil
