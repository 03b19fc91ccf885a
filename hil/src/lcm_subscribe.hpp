#pragma once
// Raw LCM subscriptions through LCM's C API: the handler gets the payload bytes and the channel.
// (LCM's C++ untyped subscription reaches its handler through a static_cast of the C callback's
// user data, which UndefinedBehaviorSanitizer's vptr check rejects.)

#include <lcm/lcm.h>
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <span>

namespace fullarm::hil::detail {

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
