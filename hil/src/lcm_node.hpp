#pragma once
// What the serving nodes (the plant node, lcm_io.cpp; the global node, lcm_search.cpp) and the
// tick's clients share: deadlines, the time in log lines, and a node's set-up: a receiving and a
// publishing LCM instance on one URL, its subscriptions and its log.

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <string>
#include <vector>

#include <lcm/lcm-cpp.hpp>

#include "fullarm/hil/io_device.hpp"
#include "lcm_subscribe.hpp"

namespace fullarm::hil::detail {

using Clock = std::chrono::steady_clock;

/// The time `s` seconds from now.
inline Clock::time_point after(double s) {
  return Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

/// Whole milliseconds until `deadline`, in [0, 1000] (an LCM handle timeout).
inline int millisUntil(Clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - Clock::now()).count();
  return static_cast<int>(std::clamp<long long>(left, 0, 1000));
}

/// "0.1 s".
inline std::string seconds(double s) {
  char text[32];
  std::snprintf(text, sizeof text, "%g s", s);
  return text;
}

/// A serving node's LCM instances (one receives, one publishes: the publisher thread sends while
/// the node's loop handles), its subscriptions and its log.
class NodeLcm {
 public:
  /// Opens `url` twice. `lines` keeps every log line, each stamped with the time since now;
  /// `on_log` (may be empty) sees each as it happens.
  /// @throws DeviceError "<node>: cannot open the LCM URL <url>"
  NodeLcm(std::string node, const std::string& url, std::vector<std::string>& lines,
          std::function<void(const std::string&)> on_log)
      : rx(url),
        tx(url),
        node_(std::move(node)),
        url_(url),
        lines_(lines),
        on_log_(std::move(on_log)),
        start_(Clock::now()) {
    if (!rx.good() || !tx.good()) throw DeviceError(node_ + ": cannot open the LCM URL " + url_);
  }
  ~NodeLcm() {
    for (lcm_subscription_t* s : subscriptions_) lcm_unsubscribe(rx.getUnderlyingLCM(), s);
  }
  NodeLcm(const NodeLcm&) = delete;
  NodeLcm& operator=(const NodeLcm&) = delete;

  /// Subscribes `handler` (subscribeRaw) to `channel` on the receiving instance.
  /// @throws DeviceError "<node>: cannot subscribe on <url>"
  template <class Handler>
  void subscribe(const char* channel, Handler* handler, int capacity) {
    lcm_subscription_t* s = subscribeRaw(rx, channel, handler, capacity);
    if (s == nullptr) throw DeviceError(node_ + ": cannot subscribe on " + url_);
    subscriptions_.push_back(s);
  }

  /// Logs `what` with the time since the node started.
  void log(const std::string& what) {
    char stamp[32];
    std::snprintf(stamp, sizeof stamp, "%.3f s: ", std::chrono::duration<double>(Clock::now() - start_).count());
    lines_.push_back(stamp + what);
    if (on_log_) on_log_(lines_.back());
  }

  lcm::LCM rx;  ///< the node's loop handles on it
  lcm::LCM tx;  ///< the node's publisher sends on it

 private:
  std::string node_;
  std::string url_;
  std::vector<std::string>& lines_;
  std::function<void(const std::string&)> on_log_;
  Clock::time_point start_;
  std::vector<lcm_subscription_t*> subscriptions_;
};

}  // namespace fullarm::hil::detail
