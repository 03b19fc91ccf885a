#pragma once
/// @file
/// The global search as a node of its own (the paper's graphics workstation, §3.1): the tick's
/// side sends each query's joint angles, the global node runs the search and answers with the
/// set of minima, fragmented (lcm_transport.hpp).
///
/// **Protocol.** A query is a joint_state_t on FULLARM_SEARCH_QUERY whose q_rad holds the arm
/// model's configuration (model order, the tick's `q`), tick = the query tick and seq = the id
/// the set will carry. The global node answers each new query with a minima set (set_id = the
/// query's seq, computed_tick = its tick, q_rad = its joint angles, num_minima_dropped = found
/// beyond the set). In lockstep the tick's side waits for each set when its delivery tick comes,
/// so a run over the global node is deterministic and equals the in-process run. A set that will
/// not come is not adopted (the tick keeps descending its old minima and the stale-minima fade
/// takes the forces down, as when the in-process search stalls): the node's heartbeat, sent only
/// after the sets queued before it, tells a lost fragment at once; a silent node costs one
/// timeout, after which sets are only taken if already there until its heartbeat returns.

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "fullarm/haptics/minima.hpp"
#include "fullarm/hil/global_search.hpp"
#include "fullarm/hil/lcm_transport.hpp"

namespace fullarm::hil {

namespace channel {
inline constexpr const char* kSearchQuery = "FULLARM_SEARCH_QUERY";
}  // namespace channel

/// What the tick's side of a remote search saw.
struct LcmSearchCounters {
  std::uint64_t queries = 0;  ///< queries sent
  std::uint64_t sets = 0;     ///< sets received in time
  std::uint64_t missed = 0;   ///< sets that did not come in time (not adopted)
};

/// The tick's side of the global search over LCM in a lockstep run.
class LcmSearchClient {
 public:
  /// Opens `url` and waits up to `connect_timeout_s` for the global node's heartbeat.
  /// @throws DeviceError when the URL cannot be opened or no global node answers
  LcmSearchClient(const std::string& url, double connect_timeout_s, double reply_timeout_s);
  ~LcmSearchClient();
  LcmSearchClient(const LcmSearchClient&) = delete;
  LcmSearchClient& operator=(const LcmSearchClient&) = delete;

  /// Sends a query: the set `set_id` at configuration `q` [rad] (model order) of tick `tick`.
  void query(std::int64_t set_id, std::uint64_t tick, const Eigen::VectorXd& q);
  /// Waits for set `set_id`, queried at `query_tick`. True with `minima` and `found` filled;
  /// false when it will not come: the global node's heartbeat reports a later or equal tick
  /// answered (a fragment was lost), or the reply timeout passed. After a timeout without any
  /// heartbeat of the node (a dead node) later calls only take sets already there, until its
  /// heartbeat returns.
  bool await(std::int64_t set_id, std::uint64_t query_tick, std::vector<haptics::LocalMinimum>& minima, int& found);

  [[nodiscard]] const LcmSearchCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const LcmReceiverCounters& receiverCounters() const noexcept { return receiver_->counters(); }

 private:
  std::unique_ptr<lcm::LCM> lcm_;
  std::unique_ptr<LcmReceiver> receiver_;
  double reply_timeout_s_;
  bool lost_ = false;  ///< the global node is silent (no heartbeat during the last wait)
  std::vector<std::uint8_t> buffer_;
  LcmSearchCounters counters_;
};

/// The tick's side of the global search over LCM in a real-time run. The tick pushes its
/// configuration every global period (`pushConfiguration`, @rt: into the publisher's ring; the
/// publisher thread sends it as a live joint_state_t on FULLARM_JOINT_STATE, with the local
/// node's heartbeat); the global node searches on the newest it has and answers with sets as
/// fast as it searches; the receiving thread (not real time) waits for them (`waitForSet`).
class LcmLiveSearchClient {
 public:
  /// Opens `url` and waits up to `connect_timeout_s` for the global node's heartbeat.
  /// @throws DeviceError when the URL cannot be opened or no global node answers
  LcmLiveSearchClient(const std::string& url, double connect_timeout_s, double heartbeat_period_s);
  ~LcmLiveSearchClient();
  LcmLiveSearchClient(const LcmLiveSearchClient&) = delete;
  LcmLiveSearchClient& operator=(const LcmLiveSearchClient&) = delete;

  /// Queues the arm model's configuration `q_rad` (`n` angles, model order) of tick `tick`;
  /// false (counted) if the ring is full. The query's seq is the tick, so the sets' ids
  /// increase with the ticks they answer. @rt
  bool pushConfiguration(std::int64_t tick, const double* q_rad, int n) noexcept;
  /// The local node's state in its heartbeat (the newest tick, safe outputs). @rt
  void setNodeState(std::int64_t tick, bool safe_output) noexcept;
  /// Waits up to `timeout_s` for a whole set; the newest arrived, or nullptr. Receiving thread.
  const MinimaSetRecord* waitForSet(double timeout_s);
  /// Sends what is queued and stops the publisher thread.
  void stop();

  [[nodiscard]] const LcmReceiver& receiver() const noexcept { return *receiver_; }
  [[nodiscard]] LcmPublisherCounters publisherCounters() const noexcept { return publisher_->counters(); }

 private:
  std::unique_ptr<lcm::LCM> tx_, rx_;
  std::unique_ptr<LcmReceiver> receiver_;
  std::unique_ptr<LcmPublisher> publisher_;
};

/// Options of the global node.
struct GlobalNodeOptions {
  std::string url = kDefaultLcmUrl;
  /// Stop after this long without a query (also before the first) [s]; <= 0: never.
  double idle_exit_s = 5.0;
  double heartbeat_period_s = 0.05;
  /// Fault injection: true drops the fragment with this sequence number unsent.
  std::function<bool(std::string_view channel, std::int64_t seq)> drop;
  /// Called with each log line as it happens.
  std::function<void(const std::string&)> on_log;
};

/// What a global node did.
struct GlobalNodeResult {
  std::uint64_t queries = 0;      ///< lockstep queries answered
  std::uint64_t live_states = 0;  ///< live joint states received (real-time runs)
  std::uint64_t live_sets = 0;    ///< sets answered to live joint states (the newest waiting each time)
  std::uint64_t stale = 0;        ///< queries or live states not newer than the last (ignored)
  std::uint64_t rejected = 0;     ///< damaged or misshapen queries (ignored)
  std::vector<std::string> log;
};

/// Serves a GlobalSearchRunner over LCM: answers every new lockstep query (FULLARM_SEARCH_QUERY)
/// with its set, in order, and in real-time runs the newest live joint state
/// (FULLARM_JOINT_STATE, model configuration in q_rad) each time the search is free.
class LcmGlobalNode {
 public:
  /// `search` must outlive the node; `num_config` is the model configuration's size.
  LcmGlobalNode(GlobalSearchRunner& search, int num_config, GlobalNodeOptions options);
  /// Serves until idle for idle_exit_s or until `stop` returns true.
  /// @throws DeviceError when the LCM URL cannot be opened
  GlobalNodeResult serve(const std::function<bool()>& stop = {});

 private:
  GlobalSearchRunner& search_;
  int num_config_;
  GlobalNodeOptions options_;
};

}  // namespace fullarm::hil
