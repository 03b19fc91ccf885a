// Every decoder of the LCM transport against damaged payloads: truncated at every length, a
// wrong type hash, trailing bytes, counts beyond their bounds or negative, random byte flips and
// random garbage. A damaged payload is never accepted as valid unless it decodes into a record
// within its bounds; nothing crashes or throws; the receiver counts each rejection and still
// accepts the next valid message.

#include <gtest/gtest.h>

#include <functional>
#include <random>
#include <string_view>

#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/lcm_transport.hpp"

namespace fullarm::hil {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes jointStateBytes() {
  JointStateRecord r;
  r.seq = 3;
  r.tick = 3;
  r.num_joints = 7;
  for (int j = 0; j < 7; ++j) r.q_rad[static_cast<std::size_t>(j)] = 0.1 * j;
  Bytes b;
  encodeMessage(toMessage(r), b);
  return b;
}

Bytes valveCommandBytes() {
  ValveCommandRecord r;
  r.seq = 3;
  r.num_valves = 7;
  for (int j = 0; j < 7; ++j) r.valve_command_v[static_cast<std::size_t>(j)] = -0.2 * j;
  Bytes b;
  encodeMessage(toMessage(r), b);
  return b;
}

Bytes heartbeatBytes() {
  HeartbeatRecord r;
  r.seq = 3;
  r.node = NodeKind::kGlobal;
  r.tick = 99;
  Bytes b;
  encodeMessage(toMessage(r), b);
  return b;
}

Bytes fragmentBytes() {
  MinimaSetRecord s;
  s.set_id = 3;
  s.num_joints = 7;
  s.num_minima = 23;
  for (int i = 0; i < s.num_minima; ++i) s.minima[static_cast<std::size_t>(i)].distance_m = 0.01 * i;
  Bytes b;
  encodeMessage(toFragment(s, 1, 3), b);
  return b;
}

Bytes ioCommandBytes() {
  fullarm_lcm::io_command_t m{};
  m.seq = 3;
  m.num_valves = 7;
  m.valve_command_v.assign(7, 1.5);
  m.enable = 1;
  Bytes b;
  encodeMessage(m, b);
  return b;
}

Bytes ioReadingBytes() {
  fullarm_lcm::io_reading_t m{};
  m.seq = 3;
  m.t_s = 0.003;
  m.num_joints = 7;
  m.q_rad.assign(7, 0.25);
  m.tau_load_cell_nm.assign(7, -4.0);
  m.pressure_mask = 1 << 3;
  m.p_a_pa.assign(7, 0.0);
  m.p_b_pa.assign(7, 0.0);
  m.p_a_pa[3] = 8.0e6;
  m.p_b_pa[3] = 6.5e6;
  Bytes b;
  encodeMessage(m, b);
  return b;
}

Bytes ioNodeInfoBytes() {
  IoNodeInfo info;
  info.joint_names = {"SFE", "SAA", "HR", "EFE", "WR", "WFE", "WAA"};
  info.period_us = 1000;
  info.scripted_user = true;
  info.plant = "dts_plant.yaml sha256 00ff";
  fullarm_lcm::io_node_info_t m = toMessage(info);
  m.seq = 3;
  Bytes b;
  encodeMessage(m, b);
  return b;
}

/// One decoder under test: its valid payload, its checked decoder, and its bounds check on a
/// record it accepted (independent of the decoder: the record's own invariants).
struct Case {
  const char* name;
  const char* channel;
  Bytes valid;
  std::function<DecodeStatus(const Bytes&)> decode;
  /// The receiver's counters of its channel; empty when LcmReceiver does not handle it.
  std::function<const LcmChannelCounters&(const LcmReceiverCounters&)> counters;
};

std::vector<Case> cases() {
  std::vector<Case> out;
  out.push_back({"joint_state_t", channel::kJointState, jointStateBytes(),
                 [](const Bytes& b) {
                   JointStateRecord r;
                   const DecodeStatus s = decodeChecked(b, r);
                   if (s == DecodeStatus::kOk) {
                     EXPECT_TRUE(r.num_joints >= 0 && r.num_joints <= kMaxRecordJoints);
                   }
                   return s;
                 },
                 [](const LcmReceiverCounters& c) -> const LcmChannelCounters& { return c.joint_state; }});
  out.push_back({"valve_command_t", channel::kValveCommand, valveCommandBytes(),
                 [](const Bytes& b) {
                   ValveCommandRecord r;
                   const DecodeStatus s = decodeChecked(b, r);
                   if (s == DecodeStatus::kOk) {
                     EXPECT_TRUE(r.num_valves >= 0 && r.num_valves <= kMaxRecordJoints);
                   }
                   return s;
                 },
                 [](const LcmReceiverCounters& c) -> const LcmChannelCounters& { return c.valve_command; }});
  out.push_back({"heartbeat_t", channel::kHeartbeat, heartbeatBytes(),
                 [](const Bytes& b) {
                   HeartbeatRecord r;
                   const DecodeStatus s = decodeChecked(b, r);
                   if (s == DecodeStatus::kOk) {
                     const int node = static_cast<int>(r.node);
                     EXPECT_TRUE(node >= 0 && node < kNodeKinds);
                   }
                   return s;
                 },
                 [](const LcmReceiverCounters& c) -> const LcmChannelCounters& { return c.heartbeat; }});
  out.push_back({"minima_set_t", channel::kMinimaSet, fragmentBytes(),
                 [](const Bytes& b) {
                   fullarm_lcm::minima_set_t f{};
                   const DecodeStatus s = decodeChecked(b, f);
                   if (s == DecodeStatus::kOk) {
                     EXPECT_TRUE(f.num_minima >= 0 && f.num_minima <= kMaxMinimaPerFragment);
                     EXPECT_EQ(f.minima.size(), static_cast<std::size_t>(f.num_minima));
                     EXPECT_TRUE(f.fragment_index >= 0 && f.fragment_index < f.fragment_count);
                     EXPECT_LE(f.first_minimum_index + f.num_minima, f.num_minima_total);
                   }
                   return s;
                 },
                 [](const LcmReceiverCounters& c) -> const LcmChannelCounters& { return c.minima_fragment; }});
  // The remote-I/O messages (no LcmReceiver channel: the device and the node decode them).
  out.push_back({"io_command_t",
                 channel::kIoCommand,
                 ioCommandBytes(),
                 [](const Bytes& b) {
                   fullarm_lcm::io_command_t m{};
                   const DecodeStatus s = decodeChecked(b, m);
                   if (s == DecodeStatus::kOk) {
                     EXPECT_TRUE(m.num_valves >= 0 && m.num_valves <= kMaxIoJoints);
                     EXPECT_EQ(m.valve_command_v.size(), static_cast<std::size_t>(m.num_valves));
                   }
                   return s;
                 },
                 {}});
  out.push_back({"io_reading_t",
                 channel::kIoReading,
                 ioReadingBytes(),
                 [](const Bytes& b) {
                   fullarm_lcm::io_reading_t m{};
                   const DecodeStatus s = decodeChecked(b, m);
                   if (s == DecodeStatus::kOk) {
                     EXPECT_TRUE(m.num_joints >= 0 && m.num_joints <= kMaxIoJoints);
                     EXPECT_EQ(m.q_rad.size(), static_cast<std::size_t>(m.num_joints));
                     EXPECT_EQ(m.tau_load_cell_nm.size(), static_cast<std::size_t>(m.num_joints));
                     EXPECT_EQ(m.p_a_pa.size(), static_cast<std::size_t>(m.num_joints));
                     EXPECT_EQ(m.p_b_pa.size(), static_cast<std::size_t>(m.num_joints));
                     EXPECT_EQ(static_cast<std::uint32_t>(m.pressure_mask) >> m.num_joints, 0u);
                   }
                   return s;
                 },
                 {}});
  out.push_back({"io_node_info_t",
                 channel::kIoNodeInfo,
                 ioNodeInfoBytes(),
                 [](const Bytes& b) {
                   fullarm_lcm::io_node_info_t m{};
                   const DecodeStatus s = decodeChecked(b, m);
                   if (s == DecodeStatus::kOk) {
                     EXPECT_TRUE(m.num_joints >= 0 && m.num_joints <= kMaxIoJoints);
                     EXPECT_EQ(m.joint_names.size(), static_cast<std::size_t>(m.num_joints));
                     for (const std::string& name : m.joint_names) {
                       EXPECT_TRUE(!name.empty() && name.size() <= kMaxNodeJointNameChars);
                       for (const char c : name) EXPECT_GE(static_cast<unsigned char>(c), 0x20);
                     }
                     EXPECT_LE(m.plant.size(), kMaxNodePlantChars);
                     EXPECT_TRUE(m.period_us > 0 && m.period_us <= kMaxNodePeriodUs);
                   }
                   return s;
                 },
                 {}});
  return out;
}

TEST(LcmDecoderFuzz, ValidPayloadsDecode) {
  for (const Case& c : cases()) EXPECT_EQ(c.decode(c.valid), DecodeStatus::kOk) << c.name;
}

TEST(LcmDecoderFuzz, EveryTruncationIsTruncated) {
  for (const Case& c : cases()) {
    for (std::size_t n = 0; n < c.valid.size(); ++n) {
      const Bytes cut(c.valid.begin(), c.valid.begin() + static_cast<std::ptrdiff_t>(n));
      EXPECT_EQ(c.decode(cut), DecodeStatus::kTruncated) << c.name << " cut to " << n << " bytes";
    }
  }
}

TEST(LcmDecoderFuzz, AnotherTypesHashIsWrongHash) {
  const std::vector<Case> all = cases();
  for (const Case& c : all) {
    for (std::size_t byte = 0; byte < 8; ++byte) {
      Bytes b = c.valid;
      b[byte] ^= 0x01;
      EXPECT_EQ(c.decode(b), DecodeStatus::kWrongHash) << c.name << " hash byte " << byte;
    }
    // Every other type's valid payload on this decoder.
    for (const Case& other : all) {
      if (&other != &c) {
        EXPECT_EQ(c.decode(other.valid), DecodeStatus::kWrongHash) << other.name << " as " << c.name;
      }
    }
  }
}

TEST(LcmDecoderFuzz, TrailingBytesAreMalformed) {
  for (const Case& c : cases()) {
    Bytes b = c.valid;
    b.push_back(0);
    EXPECT_EQ(c.decode(b), DecodeStatus::kMalformed) << c.name;
  }
}

TEST(LcmDecoderFuzz, CountsBeyondTheirBoundsOrNegativeAreRejected) {
  // joint_state_t: hash(8) utime(8) seq(8) tick(8) num_joints(1) at offset 32.
  Bytes b = jointStateBytes();
  b[32] = 0xFF;  // num_joints = -1
  EXPECT_NE(cases()[0].decode(b), DecodeStatus::kOk);
  // A well-formed message whose count exceeds the record's bound.
  fullarm_lcm::joint_state_t big = toMessage(JointStateRecord{});
  big.num_joints = static_cast<std::int8_t>(kMaxRecordJoints + 1);
  big.q_rad.assign(static_cast<std::size_t>(big.num_joints), 0.0);
  big.tau_measured_nm = big.q_rad;
  big.valve_command_v = big.q_rad;
  encodeMessage(big, b);
  EXPECT_EQ(cases()[0].decode(b), DecodeStatus::kMalformed);
  // minima_set_t: num_minima (int16) right after q_rad; a negative count is never valid.
  Bytes f = fragmentBytes();
  const std::size_t num_minima_at = 8 + 8 * 3 + 2 * 5 + 8 * 3 + 1 + 8 * 7;
  ASSERT_EQ(f[num_minima_at + 1], kMaxMinimaPerFragment);  // the fragment is full
  f[num_minima_at] = 0xFF;
  f[num_minima_at + 1] = 0xFF;
  EXPECT_NE(cases()[3].decode(f), DecodeStatus::kOk);
  // heartbeat_t: a node that does not exist. hash(8) utime(8) seq(8) node(1).
  Bytes h = heartbeatBytes();
  h[24] = 7;
  EXPECT_EQ(cases()[2].decode(h), DecodeStatus::kMalformed);
}

// io_reading_t's flag masks name joints the reading has, and nothing else.
TEST(LcmDecoderFuzz, ReadingFlagBitsBeyondTheJointsAreRejected) {
  const auto decode = [](int num_joints, std::int32_t pressure_mask, std::int32_t out_of_range_mask) {
    fullarm_lcm::io_reading_t m{};
    m.num_joints = static_cast<std::int8_t>(num_joints);
    const auto n = static_cast<std::size_t>(num_joints);
    m.q_rad.assign(n, 0.5);
    m.tau_load_cell_nm.assign(n, 1.0);
    m.p_a_pa.assign(n, 7.0e6);
    m.p_b_pa.assign(n, 6.0e6);
    m.pressure_mask = pressure_mask;
    m.out_of_range_mask = out_of_range_mask;
    Bytes b;
    encodeMessage(m, b);
    fullarm_lcm::io_reading_t out{};
    return decodeChecked(b, out);
  };
  EXPECT_EQ(decode(7, 1 << 6, 1 << 6), DecodeStatus::kOk);
  EXPECT_EQ(decode(7, 0x7F, 0), DecodeStatus::kOk);
  EXPECT_EQ(decode(7, 1 << 7, 0), DecodeStatus::kMalformed);
  EXPECT_EQ(decode(7, -1, 0), DecodeStatus::kMalformed);
  EXPECT_EQ(decode(0, 1, 0), DecodeStatus::kMalformed);
  EXPECT_EQ(decode(7, 0, 1 << 7), DecodeStatus::kMalformed);
  EXPECT_EQ(decode(kMaxIoJoints, 1 << (kMaxIoJoints - 1), 0), DecodeStatus::kOk);
  EXPECT_EQ(decode(kMaxIoJoints, 1 << kMaxIoJoints, 0), DecodeStatus::kMalformed);
}

// io_node_info_t: hash(8) utime(8) seq(8) num_joints(1), then each name as an int32 length
// (counting its NUL) and its bytes. The generated decoder would take a length of 0 or less as
// a huge one: the checked decoder refuses it before.
TEST(LcmDecoderFuzz, NodeInfoStringLengthsAndFieldsOutOfBoundsAreRejected) {
  const Case node_info = cases().back();
  ASSERT_STREQ(node_info.name, "io_node_info_t");
  const auto setLength = [](Bytes& b, std::size_t at, std::uint32_t len) {
    for (std::size_t i = 0; i < 4; ++i) b[at + i] = static_cast<std::uint8_t>(len >> (8 * (3 - i)));
  };
  const std::size_t first_name_at = 25;
  for (const std::uint32_t len : {0u, 0xFFFFFFFFu, 0x80000000u, 0x7FFFFFFFu}) {
    Bytes b = ioNodeInfoBytes();
    setLength(b, first_name_at, len);
    EXPECT_NE(node_info.decode(b), DecodeStatus::kOk) << "name length " << len;
  }
  // An empty name (length 1: the NUL alone).
  {
    IoNodeInfo info;
    info.joint_names = {"SFE", ""};
    info.period_us = 1000;
    Bytes b;
    encodeMessage(toMessage(info), b);
    EXPECT_EQ(node_info.decode(b), DecodeStatus::kMalformed);
  }
  // Names and plant at their bounds, and one character beyond.
  for (const bool beyond : {false, true}) {
    IoNodeInfo info;
    info.joint_names = {std::string(kMaxNodeJointNameChars + (beyond ? 1 : 0), 'J')};
    info.period_us = 1000;
    Bytes b;
    encodeMessage(toMessage(info), b);
    EXPECT_EQ(node_info.decode(b), beyond ? DecodeStatus::kMalformed : DecodeStatus::kOk);
    info.joint_names = {"SFE"};
    info.plant = std::string(kMaxNodePlantChars + (beyond ? 1 : 0), 'p');
    encodeMessage(toMessage(info), b);
    EXPECT_EQ(node_info.decode(b), beyond ? DecodeStatus::kMalformed : DecodeStatus::kOk);
  }
  // A control character in a name; a period that is not positive or beyond a second; a
  // negative joint count.
  {
    IoNodeInfo info;
    info.period_us = 1000;
    Bytes b;
    // C0, DEL, a C1 control and a byte of another encoding: printable ASCII only.
    for (const std::string& name :
         {std::string("SF\nE"), std::string("SF\x7F"), std::string("SF\x9B"), std::string("SF\xC3\xA9")}) {
      info.joint_names = {name};
      encodeMessage(toMessage(info), b);
      EXPECT_EQ(node_info.decode(b), DecodeStatus::kMalformed) << name;
    }
    info.joint_names = {"SFE"};
    for (const std::int32_t period_us : {0, -1000, kMaxNodePeriodUs + 1}) {
      info.period_us = period_us;
      encodeMessage(toMessage(info), b);
      EXPECT_EQ(node_info.decode(b), DecodeStatus::kMalformed) << period_us << " us";
    }
  }
  Bytes b = ioNodeInfoBytes();
  b[24] = 0xFF;  // num_joints = -1
  EXPECT_EQ(node_info.decode(b), DecodeStatus::kMalformed);
  b[24] = static_cast<std::uint8_t>(kMaxIoJoints + 1);
  EXPECT_NE(node_info.decode(b), DecodeStatus::kOk);
}

TEST(LcmDecoderFuzz, NodeInfoRoundTrips) {
  IoNodeInfo info;
  info.joint_names = {"SFE", "SAA", "HR"};
  info.period_us = 2000;
  info.simulated = false;
  info.scripted_user = true;
  info.plant = "plant.yaml sha256 abc";
  Bytes b;
  encodeMessage(toMessage(info), b);
  fullarm_lcm::io_node_info_t m{};
  ASSERT_EQ(decodeChecked(b, m), DecodeStatus::kOk);
  const IoNodeInfo back = fromMessage(m);
  EXPECT_EQ(back.joint_names, info.joint_names);
  EXPECT_EQ(back.period_us, 2000);
  EXPECT_FALSE(back.simulated);
  EXPECT_TRUE(back.scripted_user);
  EXPECT_EQ(back.plant, info.plant);
  EXPECT_EQ(describeJointsAndPeriod(back.joint_names, back.period_us), "SFE,SAA,HR every 2000 us");
}

TEST(LcmDecoderFuzz, RandomDamageNeverCrashesAndTheReceiverCountsIt) {
  std::mt19937 rng(2024);
  lcm::LCM lcm("memq://");
  for (const Case& c : cases()) {
    LcmReceiver rx(lcm, {});
    std::uint64_t fed = 0;
    std::uint64_t accepted_by_decoder = 0;
    for (int trial = 0; trial < 3000; ++trial) {
      Bytes b = c.valid;
      if (trial % 3 == 2) {
        // Garbage after the right hash.
        std::uniform_int_distribution<int> len(0, 2 * static_cast<int>(c.valid.size()));
        b.resize(8 + static_cast<std::size_t>(len(rng)));
        for (std::size_t i = 8; i < b.size(); ++i) b[i] = static_cast<std::uint8_t>(rng());
      } else {
        // One to four bytes flipped after the hash, sometimes cut short.
        std::uniform_int_distribution<std::size_t> at(8, b.size() - 1);
        const int flips = 1 + trial % 4;
        for (int k = 0; k < flips; ++k) b[at(rng)] ^= static_cast<std::uint8_t>(1 + rng() % 255);
        if (trial % 5 == 0) b.resize(at(rng));
      }
      const DecodeStatus s = c.decode(b);
      if (s == DecodeStatus::kOk) ++accepted_by_decoder;
      rx.handle(c.channel, b);
      ++fed;
    }
    if (!c.counters) continue;  // not a receiver channel
    const LcmChannelCounters& k = c.counters(rx.counters());
    EXPECT_EQ(k.received, fed) << c.name;
    // Every payload the decoder rejects, the receiver rejects and counts (a fragment can also
    // be rejected later, when its header disagrees with the set in progress).
    if (c.channel == std::string_view(channel::kMinimaSet)) {
      EXPECT_GE(k.rejected() + accepted_by_decoder, fed) << c.name;
    } else {
      EXPECT_EQ(k.rejected() + accepted_by_decoder, fed) << c.name;
    }
  }
}

TEST(LcmDecoderFuzz, TheReceiverAcceptsAValidMessageAfterDamagedOnes) {
  lcm::LCM lcm("memq://");
  LcmReceiver rx(lcm, {});
  Bytes b = jointStateBytes();
  Bytes damaged(b.begin(), b.begin() + 20);
  rx.handle(channel::kJointState, damaged);
  b[0] ^= 0x80;
  rx.handle(channel::kJointState, b);
  EXPECT_EQ(rx.takeJointState(), nullptr);
  rx.handle(channel::kJointState, jointStateBytes());
  ASSERT_NE(rx.takeJointState(), nullptr);
  EXPECT_EQ(rx.counters().joint_state.truncated, 1u);
  EXPECT_EQ(rx.counters().joint_state.wrong_hash, 1u);
  EXPECT_EQ(rx.counters().joint_state.accepted, 1u);
}

}  // namespace
}  // namespace fullarm::hil
