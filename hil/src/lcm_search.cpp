#include "fullarm/hil/lcm_search.hpp"

#include <algorithm>
#include <string_view>

#include "fullarm/hil/io_device.hpp"
#include "lcm_node.hpp"

namespace fullarm::hil {

using detail::after;
using detail::Clock;
using detail::millisUntil;
using detail::seconds;

// --- the tick's side ---------------------------------------------------------------------------

namespace {

// A receiver of minima sets and heartbeats on `lcm`, once a global node's heartbeat has been heard
// (it waits up to `connect_timeout_s`; DeviceError naming the URL otherwise).
std::unique_ptr<LcmReceiver> connectToGlobalNode(lcm::LCM& lcm, const std::string& url, double connect_timeout_s) {
  LcmReceiverOptions o;
  o.minima_set = true;
  o.heartbeat = true;
  auto receiver = std::make_unique<LcmReceiver>(lcm, o);
  const auto deadline = after(connect_timeout_s);
  while (receiver->heartbeatsFrom(NodeKind::kGlobal) == 0 && Clock::now() < deadline) {
    receiver->drainWait(static_cast<double>(millisUntil(deadline) + 1) * 1e-3);
  }
  if (receiver->heartbeatsFrom(NodeKind::kGlobal) == 0) {
    throw DeviceError("remote search: no global node answered on " + url + " within " + seconds(connect_timeout_s) +
                      " (start `fullarm global` with the same --lcm-url)");
  }
  return receiver;
}

}  // namespace

LcmSearchClient::LcmSearchClient(const std::string& url, double connect_timeout_s, double reply_timeout_s)
    : lcm_(std::make_unique<lcm::LCM>(url)), reply_timeout_s_(reply_timeout_s) {
  if (!lcm_->good()) throw DeviceError("remote search: cannot open the LCM URL " + url);
  receiver_ = connectToGlobalNode(*lcm_, url, connect_timeout_s);
}

LcmSearchClient::~LcmSearchClient() = default;

void LcmSearchClient::query(std::int64_t set_id, std::uint64_t tick, const Eigen::VectorXd& q) {
  JointStateRecord r;
  r.utime_us = 0;
  r.seq = set_id;
  r.tick = static_cast<std::int64_t>(tick);
  r.num_joints = static_cast<int>(std::min<Eigen::Index>(q.size(), kMaxRecordJoints));
  for (int j = 0; j < r.num_joints; ++j) r.q_rad[static_cast<std::size_t>(j)] = q[j];
  encodeMessage(toMessage(r), buffer_);
  (void)lcm_->publish(channel::kSearchQuery, buffer_.data(), static_cast<unsigned int>(buffer_.size()));
  ++counters_.queries;
}

bool LcmSearchClient::await(std::int64_t set_id, std::uint64_t query_tick, std::vector<haptics::LocalMinimum>& minima,
                            int& found) {
  // Each handled message is checked at once: a set completes on one fragment, so no set is
  // lost behind a newer one even when several are waiting.
  const auto deadline = after(lost_ ? 0.0 : reply_timeout_s_);
  const std::uint64_t beats_before = receiver_->heartbeatsFrom(NodeKind::kGlobal);
  for (;;) {
    const int wait_ms = lost_ ? 0 : millisUntil(deadline) + 1;
    if (lcm_->handleTimeout(wait_ms) <= 0) {
      if (lost_ || Clock::now() >= deadline) break;
      continue;
    }
    if (receiver_->heartbeatsFrom(NodeKind::kGlobal) != beats_before) lost_ = false;
    const MinimaSetRecord* s = receiver_->takeMinimaSet();
    if (s == nullptr) {
      // The node answered this query or a later one, and the set is not whole: lost.
      const HeartbeatRecord* h = receiver_->lastHeartbeat(NodeKind::kGlobal);
      if (h != nullptr && h->tick >= static_cast<std::int64_t>(query_tick)) break;
      continue;
    }
    if (s->set_id < set_id) continue;
    if (s->set_id > set_id) break;  // ours was lost on the way
    minima.clear();
    minima.reserve(static_cast<std::size_t>(s->num_minima));
    for (int i = 0; i < s->num_minima; ++i) minima.push_back(toLocalMinimum(s->minima[static_cast<std::size_t>(i)]));
    found = s->num_minima + s->num_minima_dropped;
    ++counters_.sets;
    return true;
  }
  ++counters_.missed;
  if (receiver_->heartbeatsFrom(NodeKind::kGlobal) == beats_before && Clock::now() >= deadline) lost_ = true;
  return false;
}

// --- the tick's side, real time --------------------------------------------------------------

LcmLiveSearchClient::LcmLiveSearchClient(const std::string& url, double connect_timeout_s, double heartbeat_period_s)
    : tx_(std::make_unique<lcm::LCM>(url)), rx_(std::make_unique<lcm::LCM>(url)) {
  if (!tx_->good() || !rx_->good()) throw DeviceError("remote search: cannot open the LCM URL " + url);
  receiver_ = connectToGlobalNode(*rx_, url, connect_timeout_s);
  LcmPublisherOptions po;
  po.node = NodeKind::kLocal;
  po.heartbeat_period_s = heartbeat_period_s;
  publisher_ = std::make_unique<LcmPublisher>(*tx_, po);
}

LcmLiveSearchClient::~LcmLiveSearchClient() {
  stop();
}

bool LcmLiveSearchClient::pushConfiguration(std::int64_t tick, const double* q_rad, int n) noexcept {
  JointStateRecord r;
  r.seq = tick;
  r.tick = tick;
  r.num_joints = std::min(n, kMaxRecordJoints);
  for (int j = 0; j < r.num_joints; ++j) r.q_rad[static_cast<std::size_t>(j)] = q_rad[j];
  return publisher_->pushJointState(r);
}

void LcmLiveSearchClient::setNodeState(std::int64_t tick, bool safe_output) noexcept {
  publisher_->setNodeState(tick, safe_output);
}

const MinimaSetRecord* LcmLiveSearchClient::waitForSet(double timeout_s) {
  (void)receiver_->drainWait(timeout_s);
  return receiver_->takeMinimaSet();
}

void LcmLiveSearchClient::stop() {
  if (publisher_) publisher_->stop();
}

// --- the global node ---------------------------------------------------------------------------

LcmGlobalNode::LcmGlobalNode(GlobalSearchRunner& search, int num_config, GlobalNodeOptions options)
    : search_(search), num_config_(num_config), options_(std::move(options)) {}

GlobalNodeResult LcmGlobalNode::serve(const std::function<bool()>& stop) {
  GlobalNodeResult result;
  detail::NodeLcm node("global node", options_.url, result.log, options_.on_log);
  lcm::LCM& rx = node.rx;
  const auto log = [&node](const std::string& what) { node.log(what); };

  // Lockstep queries are answered each, in order; live joint states (a real-time run) only the
  // newest of those waiting.
  struct Sink {
    JointStateRecord scratch;
    std::vector<JointStateRecord> queries;  ///< lockstep queries waiting, in arrival order
    JointStateRecord live;                  ///< the newest live joint state
    bool live_new = false;
    SequenceTracker live_seq;  ///< a restarted local node is heard again
    GlobalNodeResult* result = nullptr;
    void onMessage(std::span<const std::uint8_t> bytes, const char* channel) {
      if (decodeChecked(bytes, scratch) != DecodeStatus::kOk) {
        ++result->rejected;
        return;
      }
      if (std::string_view(channel) != channel::kJointState) {
        queries.push_back(scratch);
        return;
      }
      ++result->live_states;
      if (live_seq.accept(scratch.seq) == SequenceTracker::Verdict::kStale) {
        ++result->stale;
        return;
      }
      live = scratch;
      live_new = true;
    }
  } sink;
  sink.result = &result;
  sink.queries.reserve(256);
  node.subscribe(channel::kSearchQuery, &sink, 256);
  node.subscribe(channel::kJointState, &sink, 256);

  LcmPublisherOptions po;
  po.node = NodeKind::kGlobal;
  po.heartbeat_period_s = options_.heartbeat_period_s;
  po.drop = options_.drop;
  po.send_minima_sets_inline = true;  // the search is not the real-time loop: its sets go out at once
  LcmPublisher publisher(node.tx, po);
  log("serving the global search on " + options_.url);

  auto set = std::make_unique<MinimaSetRecord>();
  std::vector<haptics::LocalMinimum> minima;
  Eigen::VectorXd q(num_config_);
  SequenceTracker query_ids(1);  ///< a lockstep run's set ids start at 1: a new run is heard at once
  auto last_query = Clock::now();
  bool queried = false;
  bool live = false;
  // The set at `query`'s joint angles, with the query's seq as its id.
  const auto answer = [&](const JointStateRecord& query, bool lockstep) {
    const SequenceTracker::Verdict verdict = lockstep ? query_ids.accept(query.seq) : SequenceTracker::Verdict::kNewer;
    if (verdict == SequenceTracker::Verdict::kStale) {
      ++result.stale;
      return;
    }
    if (verdict == SequenceTracker::Verdict::kRestart) {
      log("queries restarted at set " + std::to_string(query.seq) + ": a new tick connected");
    }
    if (query.num_joints != num_config_) {
      ++result.rejected;
      log("a query with " + std::to_string(query.num_joints) + " joint angles ignored: the arm model has " +
          std::to_string(num_config_));
      return;
    }
    if (lockstep && !queried) log("first query");
    if (!lockstep && !live) log("first live joint state: answering the newest, as fast as the search runs");
    queried = true;
    live = live || !lockstep;
    last_query = Clock::now();
    for (int j = 0; j < num_config_; ++j) q[j] = query.q_rad[static_cast<std::size_t>(j)];
    const int found = search_.run(q, minima);
    set->utime_us = query.utime_us;
    set->seq = query.seq;
    set->set_id = query.seq;
    set->computed_tick = query.tick;
    set->computed_utime_us = query.utime_us;
    set->adopted_tick = -1;
    set->num_joints = num_config_;
    set->q_rad = query.q_rad;
    fillMinima(minima, *set);
    set->num_minima_dropped = found - set->num_minima;
    while (!publisher.pushMinimaSet(*set)) publisher.flush();  // every set goes out, in order
    publisher.setNodeState(query.tick, false);
    ++(lockstep ? result.queries : result.live_sets);
  };
  const auto idle = std::chrono::duration<double>(options_.idle_exit_s);
  for (;;) {
    if (stop && stop()) break;
    if (options_.idle_exit_s > 0.0 && Clock::now() - last_query > idle) {
      log(queried ? "no query for " + seconds(options_.idle_exit_s) + ": stopped"
                  : "no tick connected within " + seconds(options_.idle_exit_s) + ": stopped");
      break;
    }
    if (rx.handleTimeout(5) <= 0) continue;
    while (rx.handleTimeout(0) > 0) {
    }
    for (const JointStateRecord& query : sink.queries) answer(query, true);
    sink.queries.clear();
    if (sink.live_new) {
      sink.live_new = false;
      answer(sink.live, false);
    }
  }
  publisher.stop();
  return result;
}

}  // namespace fullarm::hil
