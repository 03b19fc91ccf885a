// One-way latency of the LCM transport on the loopback, in a network namespace of this
// process's own (nothing leaves it), beside LCM's own floor and the in-process hand-off, all in
// the same run so that their ratios hold on a loaded machine too:
//  - floor, 1 datagram: raw lcm_publish of one fragment-sized message on the sending thread ->
//    LCM 1.3's udpm receive thread -> its notify pipe -> lcm_handle on the receiving thread
//    (the same wait as LcmReceiver::drainWait: ppoll on LCM's descriptor, then handle);
//  - floor, k datagrams: k such messages back to back, k = the fragments of a 64-minimum set;
//    the latency is taken when the k-th is handled;
//  - the 64-minimum set sent directly: toFragment + encode of its k fragments, then k lcm_publish
//    back to back, on the sending thread -> LcmReceiver (checked decode, reassembly): the transport's work without
//    the publisher thread;
//  - the set through LcmPublisher as the global node sends it (send_minima_sets_inline: the
//    pushing thread encodes and publishes the fragments itself) and as a real-time producer
//    would (queued; the publisher thread polls every 100 µs); the cadence (push -> first
//    fragment, first -> last fragment handed to LCM) comes from the drop hook, called just
//    before each fragment is published;
//  - a joint state through LcmPublisher (polling), LcmReceiver::drainWait on the receiving side;
//  - the set through MinimaExchange (publish on one thread, a spinning reader);
//  - the encoding (toFragment + encode of the k fragments) and the decoding (decodeChecked +
//    MinimaSetAssembler) of one set on one thread.
// The send time travels in the message (steady clock, the same on both sides); the latency is
// taken when the receiver has the whole message. Samples are paced (1 kHz for joint states,
// 200 Hz for sets) as the loop sends them, and the paths take turns in four rounds so that a
// change of load falls on all of them. Prints p50 / p99 / max per path, then the ratios.
//
//   build/release/bench/hil_lcm_latency_bench [samples]   (default 2000)

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <poll.h>

#include "fullarm/hil/lcm_transport.hpp"
#include "fullarm/hil/minima_exchange.hpp"
#include "private_network.hpp"

namespace {

using namespace fullarm::hil;
using Clock = std::chrono::steady_clock;

constexpr const char* kUrl = "udpm://239.255.76.97:7697?ttl=0";
constexpr const char* kFloorChannel = "FULLARM_LATENCY_FLOOR";
constexpr int kRounds = 4;
constexpr std::chrono::microseconds kSetPeriod(5000);
constexpr std::chrono::microseconds kJointStatePeriod(1000);

std::int64_t nowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}

struct Quantiles {
  double p50 = 0.0, p99 = 0.0, max = 0.0;
  std::size_t n = 0;
};

Quantiles quantiles(std::vector<double> us) {
  Quantiles q;
  if (us.empty()) return q;
  std::sort(us.begin(), us.end());
  const auto at = [&](double f) {
    return us[std::min(us.size() - 1, static_cast<std::size_t>(f * static_cast<double>(us.size())))];
  };
  q.p50 = at(0.5);
  q.p99 = at(0.99);
  q.max = us.back();
  q.n = us.size();
  return q;
}

Quantiles report(const char* what, const std::vector<double>& us) {
  const Quantiles q = quantiles(us);
  if (q.n == 0) {
    std::printf("%-58s no samples\n", what);
    return q;
  }
  std::printf("%-58s n %5zu  p50 %8.1f us  p99 %8.1f us  max %8.1f us\n", what, q.n, q.p50, q.p99, q.max);
  return q;
}

void ratio(const char* what, const Quantiles& a, const Quantiles& b) {
  if (a.n == 0 || b.n == 0 || b.p50 <= 0.0 || b.p99 <= 0.0) return;
  std::printf("%-58s p50 %5.2fx  p99 %5.2fx\n", what, a.p50 / b.p50, a.p99 / b.p99);
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

/// Fragments of a 64-minimum set, and the encoded size of its first (full) fragment.
int setFragments() {
  return fragmentCount(64);
}
std::size_t fullFragmentBytes() {
  std::vector<std::uint8_t> b;
  encodeMessage(toFragment(set64(), 0, 0), b);
  return b.size();
}

lcm::LCM& openLcm(std::unique_ptr<lcm::LCM>& lcm) {
  lcm = std::make_unique<lcm::LCM>(kUrl);
  if (!lcm->good()) {
    std::fprintf(stderr, "hil_lcm_latency_bench: cannot open %s\n", kUrl);
    std::exit(1);
  }
  return *lcm;
}

/// Waits up to `timeout_s` for LCM's descriptor, then handles every message waiting (the wait of
/// LcmReceiver::drainWait).
void waitAndDrain(lcm::LCM& lcm, double timeout_s) {
  pollfd p{lcm.getFileno(), POLLIN, 0};
  timespec ts{0, static_cast<long>(timeout_s * 1e9)};
  if (::ppoll(&p, 1, &ts, nullptr) <= 0) return;
  if (lcm.handle() != 0) return;
  while (lcm.handleTimeout(0) > 0) {
  }
}

/// The floor: `burst` raw messages of `bytes` bytes back to back from the sending thread; the
/// latency of each burst is taken when its last message is handled [us], appended to `us`.
void floorPath(int n, int burst, std::size_t bytes, std::vector<double>& us, std::vector<double>& send_us) {
  std::unique_ptr<lcm::LCM> tx_lcm, rx_lcm;
  lcm::LCM& tx = openLcm(tx_lcm);
  lcm::LCM& rx = openLcm(rx_lcm);
  struct Sink {
    std::vector<double>* us;
    int burst;
    static void onMessage(const lcm_recv_buf_t* rbuf, const char*, void* user) {
      auto* self = static_cast<Sink*>(user);
      if (rbuf->data_size < 16) return;
      std::int64_t sent = 0, index = 0;
      std::memcpy(&sent, rbuf->data, 8);
      std::memcpy(&index, static_cast<const char*>(rbuf->data) + 8, 8);
      if (index == self->burst - 1) self->us->push_back(static_cast<double>(nowNs() - sent) * 1e-3);
    }
  } sink{&us, burst};
  lcm_subscription_t* sub = lcm_subscribe(rx.getUnderlyingLCM(), kFloorChannel, &Sink::onMessage, &sink);
  lcm_subscription_set_queue_capacity(sub, 256);
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done.load()) waitAndDrain(rx, 0.01);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // the receiver is listening
  std::vector<std::uint8_t> payload(bytes, 0);
  auto next = Clock::now();
  for (int i = 0; i < n; ++i) {
    next += kSetPeriod;
    std::this_thread::sleep_until(next);
    const std::int64_t sent = nowNs();
    std::memcpy(payload.data(), &sent, 8);
    for (std::int64_t k = 0; k < burst; ++k) {
      std::memcpy(payload.data() + 8, &k, 8);
      (void)tx.publish(kFloorChannel, payload.data(), static_cast<unsigned>(payload.size()));
    }
    send_us.push_back(static_cast<double>(nowNs() - sent) * 1e-3);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  done = true;
  reader.join();
  lcm_unsubscribe(rx.getUnderlyingLCM(), sub);
}

/// The receiving side of a set path: LcmReceiver::drainWait, latency when the set is whole.
class SetReader {
 public:
  SetReader(lcm::LCM& rx, std::vector<double>& us) : receiver_(rx, options()), us_(us) {
    thread_ = std::thread([this] {
      while (!done_.load()) {
        receiver_.drainWait(0.01);
        const std::int64_t t = nowNs();
        if (const MinimaSetRecord* s = receiver_.takeMinimaSet())
          us_.push_back(static_cast<double>(t - s->computed_utime_us) * 1e-3);
      }
    });
  }
  ~SetReader() {
    done_ = true;
    thread_.join();
  }
  SetReader(const SetReader&) = delete;
  SetReader& operator=(const SetReader&) = delete;

 private:
  static LcmReceiverOptions options() {
    LcmReceiverOptions o;
    o.minima_set = true;
    return o;
  }
  LcmReceiver receiver_;
  std::vector<double>& us_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

/// The set sent directly: every fragment encoded, then all published back to back, on the sending
/// thread.
void setDirect(int n, std::vector<double>& us, std::vector<double>& send_us) {
  std::unique_ptr<lcm::LCM> tx_lcm, rx_lcm;
  lcm::LCM& tx = openLcm(tx_lcm);
  lcm::LCM& rx = openLcm(rx_lcm);
  {
    SetReader reader(rx, us);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    MinimaSetRecord set = set64();
    const int k = fragmentCount(set.num_minima);
    std::vector<std::vector<std::uint8_t>> buffers(static_cast<std::size_t>(k));
    std::int64_t seq = 0;
    auto next = Clock::now();
    for (int i = 0; i < n; ++i) {
      next += kSetPeriod;
      std::this_thread::sleep_until(next);
      set.set_id = i;
      set.computed_utime_us = nowNs();  // carries the send time [ns]
      // As LcmPublisher does: every fragment encoded, then all sent back to back.
      for (int f = 0; f < k; ++f) encodeMessage(toFragment(set, f, seq++), buffers[static_cast<std::size_t>(f)]);
      for (const std::vector<std::uint8_t>& b : buffers) {
        (void)tx.publish(channel::kMinimaSet, b.data(), static_cast<unsigned>(b.size()));
      }
      send_us.push_back(static_cast<double>(nowNs() - set.computed_utime_us) * 1e-3);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
}

/// The set through LcmPublisher; `first`: push -> first fragment handed to LCM, `span`: first ->
/// last fragment handed to LCM [us] (the publisher's cadence).
void setPublisher(int n, bool inline_sets, std::vector<double>& us, std::vector<double>& first,
                  std::vector<double>& span) {
  std::unique_ptr<lcm::LCM> tx_lcm, rx_lcm;
  lcm::LCM& tx = openLcm(tx_lcm);
  lcm::LCM& rx = openLcm(rx_lcm);
  const int k = setFragments();
  std::vector<std::int64_t> pushed(static_cast<std::size_t>(n), 0);
  std::vector<double> first_here, span_here;
  first_here.reserve(static_cast<std::size_t>(n));
  span_here.reserve(static_cast<std::size_t>(n));
  std::int64_t first_at = 0;
  {
    SetReader reader(rx, us);
    LcmPublisherOptions po;
    po.heartbeat_period_s = 0.0;
    po.send_minima_sets_inline = inline_sets;
    // Called just before each fragment goes to LCM; drops nothing.
    po.drop = [&](std::string_view, std::int64_t seq) {
      const std::int64_t t = nowNs();
      const auto set = static_cast<std::size_t>(seq / k);
      if (set >= pushed.size()) return false;
      if (seq % k == 0) {
        first_at = t;
        first_here.push_back(static_cast<double>(t - pushed[set]) * 1e-3);
      }
      if (seq % k == k - 1) span_here.push_back(static_cast<double>(t - first_at) * 1e-3);
      return false;
    };
    LcmPublisher publisher(tx, po);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    MinimaSetRecord set = set64();
    auto next = Clock::now();
    for (int i = 0; i < n; ++i) {
      next += kSetPeriod;
      std::this_thread::sleep_until(next);
      set.set_id = i;
      pushed[static_cast<std::size_t>(i)] = nowNs();
      set.computed_utime_us = pushed[static_cast<std::size_t>(i)];  // carries the send time [ns]
      (void)publisher.pushMinimaSet(set);
    }
    publisher.flush();
    publisher.stop();
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  first.insert(first.end(), first_here.begin(), first_here.end());
  span.insert(span.end(), span_here.begin(), span_here.end());
}

/// A joint state through LcmPublisher (polling) to LcmReceiver::drainWait [us].
void jointState(int n, std::vector<double>& us) {
  std::unique_ptr<lcm::LCM> tx_lcm, rx_lcm;
  lcm::LCM& tx = openLcm(tx_lcm);
  lcm::LCM& rx = openLcm(rx_lcm);
  LcmReceiverOptions ro;
  ro.joint_state = true;
  LcmReceiver receiver(rx, ro);
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done.load()) {
      receiver.drainWait(0.01);
      const std::int64_t t = nowNs();
      if (const JointStateRecord* j = receiver.takeJointState())
        us.push_back(static_cast<double>(t - j->utime_us) * 1e-3);
    }
  });
  {
    LcmPublisherOptions po;
    po.heartbeat_period_s = 0.0;
    LcmPublisher publisher(tx, po);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    JointStateRecord js;
    js.num_joints = 7;
    auto next = Clock::now();
    for (int i = 0; i < n; ++i) {
      next += kJointStatePeriod;
      std::this_thread::sleep_until(next);
      js.seq = i;
      js.utime_us = nowNs();  // carries the send time [ns]
      (void)publisher.pushJointState(js);
    }
    publisher.flush();
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  done = true;
  reader.join();
}

/// The set through MinimaExchange [us].
void inProcess(int n, std::vector<double>& us) {
  MinimaExchange exchange;
  std::vector<double> here;
  here.reserve(static_cast<std::size_t>(n));
  std::atomic<bool> done{false};
  std::thread reader([&] {
    while (!done.load(std::memory_order_relaxed)) {
      if (const MinimaSetRecord* s = exchange.takeNewest())
        here.push_back(static_cast<double>(nowNs() - s->computed_utime_us) * 1e-3);
    }
  });
  const MinimaSetRecord set = set64();
  auto next = Clock::now();
  for (int i = 0; i < n; ++i) {
    next += kSetPeriod;
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
  us.insert(us.end(), here.begin(), here.end());
}

/// Encoding and decoding of one set on one thread [us per set].
void codec(int n, std::vector<double>& encode_us, std::vector<double>& decode_us) {
  MinimaSetRecord set = set64();
  const int k = fragmentCount(set.num_minima);
  std::vector<std::vector<std::uint8_t>> bytes(static_cast<std::size_t>(k));
  fullarm_lcm::minima_set_t fragment{};
  MinimaSetAssembler assembler;
  std::int64_t seq = 0;
  for (int i = 0; i < n; ++i) {
    set.set_id = i;
    const auto t0 = Clock::now();
    for (int f = 0; f < k; ++f) encodeMessage(toFragment(set, f, seq++), bytes[static_cast<std::size_t>(f)]);
    const auto t1 = Clock::now();
    bool complete = false;
    for (const std::vector<std::uint8_t>& b : bytes) {
      if (decodeChecked(b, fragment) == DecodeStatus::kOk) complete = assembler.add(fragment);
    }
    const auto t2 = Clock::now();
    if (!complete) std::fprintf(stderr, "hil_lcm_latency_bench: set %d not reassembled\n", i);
    encode_us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
    decode_us.push_back(std::chrono::duration<double, std::micro>(t2 - t1).count());
  }
}

}  // namespace

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::max(kRounds, std::atoi(argv[1])) : 2000;
  const std::string error = fullarm::hil::test::enterPrivateNetwork();
  if (!error.empty()) {
    std::fprintf(stderr, "hil_lcm_latency_bench: no private network namespace: %s\n", error.c_str());
    return 1;
  }
  const int k = setFragments();
  const std::size_t bytes = fullFragmentBytes();
  const int per_round = n / kRounds;
  std::vector<double> floor1, floor1_send, floor_k, floor_k_send, direct, direct_send, inl, inl_first, inl_span, poll,
      poll_first, poll_span, js, exchange, encode, decode;
  for (int r = 0; r < kRounds; ++r) {
    floorPath(per_round, 1, bytes, floor1, floor1_send);
    floorPath(per_round, k, bytes, floor_k, floor_k_send);
    setDirect(per_round, direct, direct_send);
    setPublisher(per_round, true, inl, inl_first, inl_span);
    setPublisher(per_round, false, poll, poll_first, poll_span);
    jointState(per_round, js);
    inProcess(per_round, exchange);
    codec(per_round, encode, decode);
  }
  std::printf("64-minimum set: %d fragments, %zu bytes each (full); %d rounds\n", k, bytes, kRounds);
  char label[96];
  std::snprintf(label, sizeof label, "floor: LCM udpm, 1 datagram of %zu bytes", bytes);
  const Quantiles q1 = report(label, floor1);
  report("  sender: the publish call", floor1_send);
  std::snprintf(label, sizeof label, "floor: LCM udpm, %d datagrams back to back", k);
  const Quantiles qk = report(label, floor_k);
  std::snprintf(label, sizeof label, "  sender: %d publish calls", k);
  const Quantiles qk_send = report(label, floor_k_send);
  const Quantiles qd = report("64-minimum set, sent directly (no publisher thread)", direct);
  report("  sender: encode + publish every fragment", direct_send);
  const Quantiles qi = report("64-minimum set, LcmPublisher sending sets inline", inl);
  report("  publisher: push -> first fragment to LCM", inl_first);
  report("  publisher: first -> last fragment to LCM", inl_span);
  const Quantiles qp = report("64-minimum set, LcmPublisher thread polling every 100 us", poll);
  report("  publisher: push -> first fragment to LCM", poll_first);
  const Quantiles qp_span = report("  publisher: first -> last fragment to LCM", poll_span);
  report("joint state, LcmPublisher polling every 100 us", js);
  report("MinimaExchange 64-minimum set (in process)", exchange);
  report("encode one set (toFragment + encode, every fragment)", encode);
  report("decode one set (decodeChecked + reassembly)", decode);
  std::snprintf(label, sizeof label, "ratio: floor %d datagrams / floor 1 datagram", k);
  ratio(label, qk, q1);
  std::snprintf(label, sizeof label, "ratio: %d publish calls / floor %d datagrams", k, k);
  ratio(label, qk_send, qk);
  ratio("ratio: publisher thread's first -> last / those publish calls", qp_span, qk_send);
  std::snprintf(label, sizeof label, "ratio: set sent directly / floor %d datagrams", k);
  ratio(label, qd, qk);
  std::snprintf(label, sizeof label, "ratio: set, sent inline / floor %d datagrams", k);
  ratio(label, qi, qk);
  std::snprintf(label, sizeof label, "ratio: set, publisher thread / floor %d datagrams", k);
  ratio(label, qp, qk);
  if (qk.n > 0) std::printf("%-58s %.2fx the floor's p99\n", "goal (p99 <= 250 us)", 250.0 / qk.p99);
  return 0;
}
