// One-way latency of the LCM transport on the loopback, in a network namespace of this
// process's own (nothing leaves it), beside the in-process hand-off in the same run:
//  - a joint state: LcmPublisher::pushJointState on one thread -> the publisher thread encodes
//    and sends -> udpm -> LcmReceiver::drainWait on another thread, with its own LCM instance;
//  - a 64-minimum set: pushMinimaSet -> 7 fragments -> reassembled on the receiver;
//  - the same 64-minimum set through MinimaExchange (publish on one thread, a spinning reader).
// The send time travels in the message (steady clock, the same on both sides); the latency is
// taken when the receiver has the whole message. Samples are paced (1 kHz for joint states,
// 200 Hz for sets) as the loop sends them. Prints p50 / p99 / max per path.
//
//   build/release/bench/hil_lcm_latency_bench [samples]   (default 2000)

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <thread>
#include <vector>

#include "fullarm/hil/lcm_transport.hpp"
#include "fullarm/hil/minima_exchange.hpp"
#include "private_network.hpp"

namespace {

using namespace fullarm::hil;
using Clock = std::chrono::steady_clock;

constexpr const char* kUrl = "udpm://239.255.76.97:7697?ttl=0";

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

void report(const char* what, std::vector<double> us) {
  if (us.empty()) {
    std::printf("%-44s no samples\n", what);
    return;
  }
  std::sort(us.begin(), us.end());
  const auto at = [&](double q) {
    return us[std::min(us.size() - 1, static_cast<std::size_t>(q * static_cast<double>(us.size())))];
  };
  std::printf("%-44s n %5zu  p50 %8.1f us  p99 %8.1f us  max %8.1f us\n", what, us.size(), at(0.5), at(0.99),
              us.back());
}

MinimaSetRecord set64() {
  MinimaSetRecord s;
  s.num_joints = 7;
  s.num_minima = 64;
  for (int i = 0; i < 64; ++i) {
    s.minima[static_cast<std::size_t>(i)].link = i % 7;
    s.minima[static_cast<std::size_t>(i)].distance_m = 0.001 * i;
  }
  return s;
}

/// One-way latencies over LCM [us]: `n` messages paced `period` apart.
std::vector<double> overLcm(int n, std::chrono::microseconds period, bool minima) {
  lcm::LCM tx(kUrl);
  lcm::LCM rx(kUrl);
  if (!tx.good() || !rx.good()) {
    std::fprintf(stderr, "hil_lcm_latency_bench: cannot open %s\n", kUrl);
    std::exit(1);
  }
  LcmReceiverOptions ro;
  ro.joint_state = !minima;
  ro.minima_set = minima;
  LcmReceiver receiver(rx, ro);
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(n));
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done.load()) {
      receiver.drainWait(0.01);
      const std::int64_t t = nowNs();
      if (minima) {
        if (const MinimaSetRecord* s = receiver.takeMinimaSet())
          us.push_back(static_cast<double>(t - s->computed_utime_us) * 1e-3);
      } else if (const JointStateRecord* j = receiver.takeJointState()) {
        us.push_back(static_cast<double>(t - j->utime_us) * 1e-3);
      }
    }
  });
  {
    LcmPublisherOptions po;
    po.heartbeat_period_s = 0.0;
    LcmPublisher publisher(tx, po);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the receiver is listening
    MinimaSetRecord set = set64();
    JointStateRecord js;
    js.num_joints = 7;
    auto next = Clock::now();
    for (int i = 0; i < n; ++i) {
      next += period;
      std::this_thread::sleep_until(next);
      if (minima) {
        set.set_id = i;
        set.computed_utime_us = nowNs();  // carries the send time [ns]
        (void)publisher.pushMinimaSet(set);
      } else {
        js.seq = i;
        js.utime_us = nowNs();  // carries the send time [ns]
        (void)publisher.pushJointState(js);
      }
    }
    publisher.flush();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  done = true;
  reader.join();
  return us;
}

/// One-way latencies through MinimaExchange [us].
std::vector<double> inProcess(int n, std::chrono::microseconds period) {
  MinimaExchange exchange;
  std::vector<double> us;
  us.reserve(static_cast<std::size_t>(n));
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done.load(std::memory_order_relaxed)) {
      if (const MinimaSetRecord* s = exchange.takeNewest())
        us.push_back(static_cast<double>(nowNs() - s->computed_utime_us) * 1e-3);
    }
  });
  const MinimaSetRecord set = set64();
  auto next = Clock::now();
  for (int i = 0; i < n; ++i) {
    next += period;
    std::this_thread::sleep_until(next);
    MinimaSetRecord& slot = exchange.writeSlot();
    slot = set;
    slot.set_id = i;
    slot.computed_utime_us = nowNs();
    exchange.publish();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(10));
  done = true;
  reader.join();
  return us;
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::max(1, std::atoi(argv[1])) : 2000;
  const std::string error = fullarm::hil::test::enterPrivateNetwork();
  if (!error.empty()) {
    std::fprintf(stderr, "hil_lcm_latency_bench: no private network namespace: %s\n", error.c_str());
    return 1;
  }
  report("LCM udpm joint state (publisher thread)", overLcm(n, std::chrono::microseconds(1000), false));
  report("LCM udpm 64-minimum set (7 fragments)", overLcm(n, std::chrono::microseconds(5000), true));
  report("MinimaExchange 64-minimum set (in process)", inProcess(n, std::chrono::microseconds(5000)));
  return 0;
}
