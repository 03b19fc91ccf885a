#pragma once
// Raw LCM subscriptions through LCM's C API: the handler gets the payload bytes and the channel.
// (LCM's C++ untyped subscription reaches its handler through a static_cast of the C callback's
// user data, which UndefinedBehaviorSanitizer's vptr check rejects.)

#include <lcm/lcm.h>
#include <lcm/lcm-cpp.hpp>

#include <poll.h>

#include <cmath>
#include <cstdint>
#include <span>

namespace fullarm::hil::detail {

/// Handles one message if one arrives within `timeout_s` (to the microsecond: LCM's own
/// handleTimeout counts whole milliseconds, too coarse for a reply due within a 1 ms period).
/// 1 if a message was handled, 0 on timeout, -1 on error.
inline int handleWithin(lcm::LCM& lcm, double timeout_s) {
  pollfd p{lcm.getFileno(), POLLIN, 0};
  const double t = timeout_s > 0.0 ? timeout_s : 0.0;
  timespec ts{static_cast<time_t>(t), static_cast<long>(std::fmod(t, 1.0) * 1e9)};
  const int ready = ::ppoll(&p, 1, &ts, nullptr);
  if (ready <= 0) return ready;
  return lcm.handle() == 0 ? 1 : -1;
}

/// Subscribes `handler->onMessage(std::span<const std::uint8_t>, const char* channel)` to
/// `channel` on `lcm` with a queue of `capacity` messages; nullptr on failure. Unsubscribe with
/// lcm_unsubscribe(lcm.getUnderlyingLCM(), subscription).
template <class Handler>
lcm_subscription_t* subscribeRaw(lcm::LCM& lcm, const char* channel, Handler* handler, int capacity) {
  auto callback = [](const lcm_recv_buf_t* rbuf, const char* ch, void* user) {
    static_cast<Handler*>(user)->onMessage(
        std::span<const std::uint8_t>(static_cast<const std::uint8_t*>(rbuf->data), rbuf->data_size), ch);
  };
  lcm_subscription_t* s = lcm_subscribe(lcm.getUnderlyingLCM(), channel, callback, handler);
  if (s != nullptr) lcm_subscription_set_queue_capacity(s, capacity);
  return s;
}

}  // namespace fullarm::hil::detail
