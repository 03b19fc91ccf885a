#include "fullarm/hil/log_records.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numeric>
#include <random>
#include <vector>

#include "alloc_guard.hpp"

namespace fullarm::hil {
namespace {

bool sameBits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

haptics::LocalMinimum makeMinimum(int i) {
  haptics::LocalMinimum m;
  m.link = i % 7;
  m.object = i % 3;
  m.tri_link = 100 + i;
  m.tri_object = 200 + i;
  m.feature_link = {haptics::FeatureKind::kEdge, 10 + i};
  m.feature_object = {haptics::FeatureKind::kVertex, 20 + i};
  m.p_L = {0.1 * i, -0.2, 1.0 / 3.0 + i};
  m.p_O = {std::nextafter(0.5, 1.0), 2.0 * i, -1e-300};
  m.distance_m = 0.001 * ((i * 37) % 101);
  m.u_W = Eigen::Vector3d(1.0, 2.0, i).normalized();
  m.previous_distance_m = (i % 2 == 0) ? std::numeric_limits<double>::quiet_NaN() : 0.25 * i;
  return m;
}

void expectSameMinimum(const haptics::LocalMinimum& a, const haptics::LocalMinimum& b) {
  EXPECT_EQ(a.link, b.link);
  EXPECT_EQ(a.object, b.object);
  EXPECT_EQ(a.tri_link, b.tri_link);
  EXPECT_EQ(a.tri_object, b.tri_object);
  EXPECT_TRUE(a.feature_link == b.feature_link);
  EXPECT_TRUE(a.feature_object == b.feature_object);
  for (int k = 0; k < 3; ++k) {
    EXPECT_TRUE(sameBits(a.p_L[k], b.p_L[k]));
    EXPECT_TRUE(sameBits(a.p_O[k], b.p_O[k]));
    EXPECT_TRUE(sameBits(a.u_W[k], b.u_W[k]));
  }
  EXPECT_TRUE(sameBits(a.distance_m, b.distance_m));
  EXPECT_TRUE(sameBits(a.previous_distance_m, b.previous_distance_m));
}

MinimaSetRecord makeSet(std::int64_t id, int num_minima) {
  MinimaSetRecord set;
  set.utime_us = 1000 * id;
  set.seq = id;
  set.set_id = id;
  set.computed_tick = 10 * id;
  set.computed_utime_us = 10000 * id;
  set.adopted_tick = 10 * id + 3;
  set.num_joints = 7;
  for (int j = 0; j < 7; ++j) set.q_rad[static_cast<std::size_t>(j)] = 0.1 * j - 0.01 * static_cast<double>(id);
  std::vector<haptics::LocalMinimum> minima;
  for (int i = 0; i < num_minima; ++i) minima.push_back(makeMinimum(i + static_cast<int>(id)));
  fillMinima(minima, set);
  return set;
}

void expectSameSet(const MinimaSetRecord& a, const MinimaSetRecord& b) {
  EXPECT_EQ(a.set_id, b.set_id);
  EXPECT_EQ(a.computed_tick, b.computed_tick);
  EXPECT_EQ(a.computed_utime_us, b.computed_utime_us);
  EXPECT_EQ(a.adopted_tick, b.adopted_tick);
  ASSERT_EQ(a.num_joints, b.num_joints);
  for (int j = 0; j < a.num_joints; ++j)
    EXPECT_TRUE(sameBits(a.q_rad[static_cast<std::size_t>(j)], b.q_rad[static_cast<std::size_t>(j)]));
  ASSERT_EQ(a.num_minima, b.num_minima);
  EXPECT_EQ(a.num_minima_dropped, b.num_minima_dropped);
  for (int i = 0; i < a.num_minima; ++i) {
    expectSameMinimum(toLocalMinimum(a.minima[static_cast<std::size_t>(i)]),
                      toLocalMinimum(b.minima[static_cast<std::size_t>(i)]));
  }
}

TEST(LogRecords, MinimumRoundTripIsBitExact) {
  for (int i = 0; i < 5; ++i) {
    const haptics::LocalMinimum m = makeMinimum(i);
    haptics::LocalMinimum back;
    EXPECT_NO_HEAP_ALLOCATION(back = toLocalMinimum(toMinimumRecord(m)));
    expectSameMinimum(m, back);
  }
}

TEST(LogRecords, FillMinimaKeepsTheClosestInTheirOrder) {
  // 300 minima with shuffled, partly equal distances: the kept ones are exactly the
  // kMaxMinimaPerSet smallest by (distance, index), found here by a full sort.
  std::vector<haptics::LocalMinimum> minima;
  std::mt19937 rng(7);
  for (int i = 0; i < 300; ++i) {
    haptics::LocalMinimum m = makeMinimum(i);
    m.distance_m = 0.001 * static_cast<double>(rng() % 150);
    minima.push_back(m);
  }
  std::vector<int> order(minima.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return minima[static_cast<std::size_t>(a)].distance_m < minima[static_cast<std::size_t>(b)].distance_m;
  });
  std::vector<int> expected(order.begin(), order.begin() + kMaxMinimaPerSet);
  std::sort(expected.begin(), expected.end());

  MinimaSetRecord set;
  EXPECT_NO_HEAP_ALLOCATION(fillMinima(minima, set));
  ASSERT_EQ(set.num_minima, kMaxMinimaPerSet);
  EXPECT_EQ(set.num_minima_dropped, 300 - kMaxMinimaPerSet);
  for (int k = 0; k < kMaxMinimaPerSet; ++k) {
    EXPECT_EQ(set.minima[static_cast<std::size_t>(k)].tri_link, 100 + expected[static_cast<std::size_t>(k)]) << k;
  }
}

TEST(LogRecords, FillMinimaKeepsASmallSetWhole) {
  const MinimaSetRecord set = makeSet(1, 5);
  EXPECT_EQ(set.num_minima, 5);
  EXPECT_EQ(set.num_minima_dropped, 0);
  expectSameMinimum(toLocalMinimum(set.minima[2]), makeMinimum(3));
}

TEST(LogRecords, JointStateRoundTripsThroughItsEncodedMessage) {
  JointStateRecord r;
  r.utime_us = 123456789;
  r.seq = 42;
  r.tick = 41;
  r.num_joints = 7;
  for (int j = 0; j < 7; ++j) {
    r.q_rad[static_cast<std::size_t>(j)] = std::sin(j + 0.5);
    r.tau_measured_nm[static_cast<std::size_t>(j)] = -3.0 * j;
    r.valve_command_v[static_cast<std::size_t>(j)] = 0.1 * j;
  }
  r.input_flags = 0x5;
  const fullarm_lcm::joint_state_t m = toMessage(r);
  std::vector<std::uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  fullarm_lcm::joint_state_t decoded{};
  ASSERT_EQ(decoded.decode(buf.data(), 0, static_cast<int>(buf.size())), static_cast<int>(buf.size()));
  const JointStateRecord back = fromMessage(decoded);
  EXPECT_EQ(back.utime_us, r.utime_us);
  EXPECT_EQ(back.seq, r.seq);
  EXPECT_EQ(back.tick, r.tick);
  EXPECT_EQ(back.num_joints, 7);
  EXPECT_EQ(back.q_rad, r.q_rad);
  EXPECT_EQ(back.tau_measured_nm, r.tau_measured_nm);
  EXPECT_EQ(back.valve_command_v, r.valve_command_v);
  EXPECT_EQ(back.input_flags, r.input_flags);
}

TEST(LogRecords, HapticStatusValveCommandAndEventRoundTrip) {
  HapticStatusRecord h;
  h.tick = 9;
  h.mode = LoggedMode::kHandOnly;
  h.active_springs = 3;
  h.num_minima_tracked = 12;
  h.minima_set_id = 4;
  h.contact_scale = 0.75;
  h.num_joints = 7;
  h.num_links = 7;
  h.tau_contact_nm[3] = 1.5;
  h.links[6].force_world_n = {1.0, -2.0, 3.0};
  h.links[6].penetrating = true;
  h.links[6].total_penetration_s = 0.02;
  const HapticStatusRecord hb = fromMessage(toMessage(h));
  EXPECT_EQ(hb.mode, LoggedMode::kHandOnly);
  EXPECT_EQ(hb.minima_set_id, 4);
  EXPECT_EQ(hb.contact_scale, 0.75);
  EXPECT_EQ(hb.tau_contact_nm, h.tau_contact_nm);
  EXPECT_EQ(hb.links[6].force_world_n, h.links[6].force_world_n);
  EXPECT_TRUE(hb.links[6].penetrating);
  EXPECT_FALSE(hb.links[5].penetrating);

  ValveCommandRecord v;
  v.num_valves = 4;
  v.valve_command_v = {0.5, -0.5, 0.0, 9.75};
  v.safe_output = true;
  const ValveCommandRecord vb = fromMessage(toMessage(v));
  EXPECT_EQ(vb.valve_command_v, v.valve_command_v);
  EXPECT_TRUE(vb.safe_output);

  SupervisorEventRecord e;
  e.cause_code = 17;
  e.severity = EventSeverity::kEStop;
  e.joint = 2;
  e.value = 3.5;
  e.limit = 3.0;
  e.setMessage("joint 2 velocity 3.5 rad/s beyond its limit 3 rad/s");
  const SupervisorEventRecord eb = fromMessage(toMessage(e));
  EXPECT_EQ(eb.messageView(), "joint 2 velocity 3.5 rad/s beyond its limit 3 rad/s");
  EXPECT_EQ(eb.severity, EventSeverity::kEStop);
  EXPECT_EQ(eb.joint, 2);
}

TEST(LogRecords, EventMessageIsCutAtItsBufferWithoutAllocating) {
  SupervisorEventRecord e;
  const std::string long_text(300, 'x');
  EXPECT_NO_HEAP_ALLOCATION(e.setMessage(long_text));
  EXPECT_EQ(e.messageView().size(), static_cast<std::size_t>(kMaxEventMessageChars));
}

TEST(LogRecords, FromMessageRejectsCountsBeyondTheRecord) {
  fullarm_lcm::joint_state_t m{};
  m.num_joints = kMaxRecordJoints + 1;
  m.q_rad.assign(static_cast<std::size_t>(m.num_joints), 0.0);
  m.tau_measured_nm = m.q_rad;
  m.valve_command_v = m.q_rad;
  try {
    (void)fromMessage(m);
    FAIL() << "no error";
  } catch (const RecordError& e) {
    EXPECT_NE(std::string(e.what()).find("num_joints = 11"), std::string::npos) << e.what();
  }
}

TEST(LogRecords, AFullFragmentFitsOneDatagram) {
  // The largest fragment: kMaxMinimaPerFragment minima, kMaxRecordJoints joint angles.
  MinimaSetRecord set = makeSet(3, kMaxMinimaPerSet);
  set.num_joints = kMaxRecordJoints;
  const fullarm_lcm::minima_set_t f = toFragment(set, 0, 0);
  EXPECT_EQ(f.num_minima, kMaxMinimaPerFragment);
  EXPECT_EQ(f.getEncodedSize(), 1359);
  // On the wire LCM adds its short-message header (8 bytes) and the channel with its NUL.
  const int datagram = f.getEncodedSize() + 8 + static_cast<int>(std::strlen(channel::kMinimaSet)) + 1;
  EXPECT_LT(datagram, 1400);
}

TEST(LogRecords, FragmentCounts) {
  EXPECT_EQ(fragmentCount(0), 1);
  EXPECT_EQ(fragmentCount(1), 1);
  EXPECT_EQ(fragmentCount(kMaxMinimaPerFragment), 1);
  EXPECT_EQ(fragmentCount(kMaxMinimaPerFragment + 1), 2);
  EXPECT_EQ(fragmentCount(kMaxMinimaPerSet), (kMaxMinimaPerSet + kMaxMinimaPerFragment - 1) / kMaxMinimaPerFragment);
  EXPECT_THROW((void)toFragment(makeSet(1, 5), 1, 0), RecordError);
}

TEST(LogRecords, FragmentsReassembleInAnyOrder) {
  for (const int n : {0, 1, 10, 11, 57, kMaxMinimaPerSet}) {
    const MinimaSetRecord set = makeSet(5, n);
    std::vector<fullarm_lcm::minima_set_t> fragments;
    for (int i = 0; i < fragmentCount(n); ++i) fragments.push_back(toFragment(set, i, 100 + i));
    std::mt19937 rng(static_cast<unsigned>(n));
    std::shuffle(fragments.begin(), fragments.end(), rng);
    MinimaSetAssembler assembler;
    for (std::size_t i = 0; i < fragments.size(); ++i) {
      EXPECT_EQ(assembler.add(fragments[i]), i + 1 == fragments.size()) << n << " " << i;
    }
    expectSameSet(assembler.set(), set);
  }
}

// A set split in the earlier layout, sliced here from the current fragments' minima.
std::vector<fullarm_lcm::minima_set_t> legacyFragments(const MinimaSetRecord& set) {
  const int total = set.num_minima;
  std::vector<fullarm_lcm::minimum_t> minima;
  for (int i = 0; i < fragmentCount(total); ++i) {
    const fullarm_lcm::minima_set_t f = toFragment(set, i, 0);
    minima.insert(minima.end(), f.minima.begin(), f.minima.end());
  }
  const int count = total == 0 ? 1 : (total + kLegacyMinimaPerFragment - 1) / kLegacyMinimaPerFragment;
  std::vector<fullarm_lcm::minima_set_t> out;
  for (int i = 0; i < count; ++i) {
    fullarm_lcm::minima_set_t f = toFragment(set, 0, 50 + i);  // the header
    f.fragment_index = static_cast<std::int16_t>(i);
    f.fragment_count = static_cast<std::int16_t>(count);
    const int first = i * kLegacyMinimaPerFragment;
    const int n = std::min(kLegacyMinimaPerFragment, total - first);
    f.first_minimum_index = static_cast<std::int16_t>(first);
    f.num_minima = static_cast<std::int16_t>(n);
    f.minima.clear();
    for (int k = 0; k < n; ++k) f.minima.push_back(minima[static_cast<std::size_t>(first + k)]);
    out.push_back(f);
  }
  return out;
}

TEST(LogRecords, SetsInTheEarlierTenMinimumLayoutStillReassemble) {
  for (const int n : {0, 7, 10, 11, 20, 21, 64, kMaxMinimaPerSet}) {
    const MinimaSetRecord set = makeSet(9, n);
    std::vector<fullarm_lcm::minima_set_t> fragments = legacyFragments(set);
    for (const auto& f : fragments) {
      // Sets of up to ten minima are one fragment, the same in both layouts.
      EXPECT_EQ(checkFragment(f), n > kLegacyMinimaPerFragment ? kLegacyMinimaPerFragment : kMaxMinimaPerFragment) << n;
    }
    std::mt19937 rng(static_cast<unsigned>(n) + 7U);
    std::shuffle(fragments.begin(), fragments.end(), rng);
    MinimaSetAssembler assembler;
    for (std::size_t i = 0; i < fragments.size(); ++i) {
      EXPECT_EQ(assembler.add(fragments[i]), i + 1 == fragments.size()) << n << " " << i;
    }
    expectSameSet(assembler.set(), set);
  }
}

TEST(LogRecords, ASetMixingTheTwoLayoutsIsRejected) {
  // 20 minima: two fragments in either layout (11 + 9, or 10 + 10), so only the layout differs.
  const MinimaSetRecord set = makeSet(4, 20);
  const std::vector<fullarm_lcm::minima_set_t> legacy = legacyFragments(set);
  ASSERT_EQ(legacy.size(), 2u);
  ASSERT_EQ(fragmentCount(20), 2);
  MinimaSetAssembler assembler;
  EXPECT_FALSE(assembler.add(toFragment(set, 0, 0)));
  EXPECT_THROW(assembler.add(legacy[1]), RecordError);
  // A fragment that fits neither layout names what the current one expects.
  fullarm_lcm::minima_set_t f = legacy[1];
  f.first_minimum_index = 12;
  try {
    (void)checkFragment(f);
    FAIL() << "no error";
  } catch (const RecordError& e) {
    EXPECT_NE(std::string(e.what()).find("expected 11 .. +9"), std::string::npos) << e.what();
  }
}

TEST(LogRecords, AssemblerAbandonsAnIncompleteSetAndIgnoresStaleFragments) {
  const MinimaSetRecord a = makeSet(1, 35);  // 4 fragments
  const MinimaSetRecord b = makeSet(2, 15);  // 2 fragments
  MinimaSetAssembler assembler;
  EXPECT_FALSE(assembler.add(toFragment(a, 0, 0)));
  EXPECT_FALSE(assembler.add(toFragment(a, 1, 1)));
  EXPECT_FALSE(assembler.add(toFragment(b, 1, 2)));  // a newer set: a is given up
  EXPECT_EQ(assembler.abandoned(), 1u);
  EXPECT_FALSE(assembler.add(toFragment(a, 2, 3)));  // older than b: ignored
  EXPECT_FALSE(assembler.add(toFragment(b, 1, 4)));  // repeated: ignored
  EXPECT_EQ(assembler.ignored(), 2u);
  EXPECT_TRUE(assembler.add(toFragment(b, 0, 5)));
  expectSameSet(assembler.set(), b);
}

TEST(LogRecords, CheckFragmentNamesWhatIsInconsistent) {
  const MinimaSetRecord set = makeSet(1, 25);
  fullarm_lcm::minima_set_t f = toFragment(set, 2, 0);
  f.fragment_count = 7;
  try {
    (void)checkFragment(f);
    FAIL() << "no error";
  } catch (const RecordError& e) {
    EXPECT_NE(std::string(e.what()).find("fragment_count = 7, expected 3"), std::string::npos) << e.what();
  }
  f = toFragment(set, 2, 0);
  f.first_minimum_index = 10;
  EXPECT_THROW((void)checkFragment(f), RecordError);
  f = toFragment(set, 2, 0);
  f.minima[0].feature_link_kind = 5;
  EXPECT_THROW((void)checkFragment(f), RecordError);
  MinimaSetAssembler assembler;
  EXPECT_FALSE(assembler.add(toFragment(set, 0, 0)));
  f = toFragment(set, 1, 0);
  f.computed_tick += 1;
  EXPECT_THROW(assembler.add(f), RecordError);  // disagrees with fragment 0
}

}  // namespace
}  // namespace fullarm::hil
