// The string-length walk run before lcm-gen's decoder (lcm_layout.hpp): every message type with a
// string in hil/lcm/ has one; a valid message passes; a string length of 0, -1, INT32_MIN or past
// the payload's end, and a negative array count, are refused for every string of every walked
// type, as is a payload cut short or one byte longer; and whatever the walk passes of randomly
// damaged messages decodes, whole and without throwing.

#include "fullarm/hil/lcm_layout.hpp"

#include <gtest/gtest.h>

#include <climits>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "arm_test_util.hpp"
namespace fullarm::hil {
namespace {

using Bytes = std::vector<std::uint8_t>;

template <class Message>
Bytes encode(const Message& m) {
  Bytes b(static_cast<std::size_t>(m.getEncodedSize()));
  EXPECT_EQ(m.encode(b.data(), 0, static_cast<int>(b.size())), static_cast<int>(b.size()));
  return b;
}

fullarm_lcm::run_header_t header() {
  fullarm_lcm::run_header_t h{};
  h.utime = 1;
  h.seq = 0;
  h.wall_utime = 2;
  h.fullarm_version = "1.0";
  h.command_line = "fullarm run";
  h.io = "sim";
  h.clock = "lockstep";
  h.mode = "full-arm";
  h.seed = 3;
  h.tick_period_us = 1000;
  h.files.resize(2);
  h.files[0].role = "arm";
  h.files[0].path = "config/dts_master.yaml";
  h.files[0].sha256 = "00ff";
  h.files[1].role = "plant";
  h.files[1].path = "";  // an empty string is a length of 1 (the NUL)
  h.files[1].sha256 = "11";
  h.num_files = 2;
  h.parameters.resize(1);
  h.parameters[0].key = "duration_s";
  h.parameters[0].value = "2";
  h.num_parameters = 1;
  return h;
}

fullarm_lcm::supervisor_event_t event() {
  fullarm_lcm::supervisor_event_t e{};
  e.utime = 5;
  e.seq = 1;
  e.tick = 7;
  e.cause_code = 3;
  e.severity = 2;
  e.joint = -1;
  e.value = 1.5;
  e.limit = 1.0;
  e.message = "valve command out of range";
  return e;
}

fullarm_lcm::ident_experiment_t experiment() {
  fullarm_lcm::ident_experiment_t x{};
  x.utime = 9;
  x.fullarm_version = "1.0";
  x.command_line = "fullarm identify";
  x.source = "sim";
  x.joint = "R_EB";
  x.sample_period_s = 0.001;
  x.num_held = 2;
  x.held_joints = {"R_SFE", "R_SAA"};
  x.num_pressures = 2;
  return x;
}

/// Byte offsets of every string length in `bytes`, found by encoding `m` with each string in turn
/// made one character longer and seeing where the encodings first differ (independent of the
/// walk under test).
template <class Message, class Strings>
std::vector<std::size_t> stringLengthOffsets(const Message& m, Strings strings) {
  const Bytes base = encode(m);
  std::vector<std::size_t> offsets;
  Message copy = m;
  for (std::string* s : strings(copy)) {
    s->push_back('x');
    const Bytes longer = encode(copy);
    s->pop_back();
    std::size_t at = 0;
    while (at < base.size() && base[at] == longer[at]) ++at;
    // The length is the int32 that changed: its last byte is the first that differs.
    offsets.push_back(at - 3);
  }
  return offsets;
}

void setInt32(Bytes& b, std::size_t at, std::int32_t v) {
  const auto u = static_cast<std::uint32_t>(v);
  b[at] = static_cast<std::uint8_t>(u >> 24);
  b[at + 1] = static_cast<std::uint8_t>(u >> 16);
  b[at + 2] = static_cast<std::uint8_t>(u >> 8);
  b[at + 3] = static_cast<std::uint8_t>(u);
}

/// The walk passes `m`, and refuses each of its strings' lengths set out of range.
template <class Message, class Strings>
void expectEveryBadLengthRefused(const Message& m, Strings strings) {
  const Bytes good = encode(m);
  ASSERT_TRUE(stringLengthsInPayload(good, &m));
  const std::vector<std::size_t> offsets = stringLengthOffsets(m, strings);
  ASSERT_FALSE(offsets.empty());
  for (const std::size_t at : offsets) {
    const auto rest = static_cast<std::int64_t>(good.size() - at - 4);
    for (const std::int64_t len :
         {std::int64_t{0}, std::int64_t{-1}, std::int64_t{INT32_MIN}, std::int64_t{INT32_MAX}, rest + 1}) {
      Bytes bad = good;
      setInt32(bad, at, static_cast<std::int32_t>(len));
      EXPECT_FALSE(stringLengthsInPayload(bad, &m)) << "string length at byte " << at << " set to " << len;
    }
  }
  // Cut anywhere, or one byte longer: refused (the walk ends at the payload's end).
  for (std::size_t n = 0; n < good.size(); ++n) {
    const Bytes cut(good.begin(), good.begin() + static_cast<std::ptrdiff_t>(n));
    EXPECT_FALSE(stringLengthsInPayload(cut, &m)) << "cut at " << n;
  }
  Bytes longer = good;
  longer.push_back(0);
  EXPECT_FALSE(stringLengthsInPayload(longer, &m));
}

TEST(LcmLayout, EveryStringLengthOutOfRangeIsRefused) {
  expectEveryBadLengthRefused(header(), [](fullarm_lcm::run_header_t& h) {
    std::vector<std::string*> s = {&h.fullarm_version, &h.command_line, &h.io, &h.clock, &h.mode};
    for (auto& f : h.files) {
      s.push_back(&f.role);
      s.push_back(&f.path);
      s.push_back(&f.sha256);
    }
    for (auto& p : h.parameters) {
      s.push_back(&p.key);
      s.push_back(&p.value);
    }
    return s;
  });
  expectEveryBadLengthRefused(event(),
                              [](fullarm_lcm::supervisor_event_t& e) { return std::vector<std::string*>{&e.message}; });
  expectEveryBadLengthRefused(experiment(), [](fullarm_lcm::ident_experiment_t& x) {
    std::vector<std::string*> s = {&x.fullarm_version, &x.command_line, &x.source, &x.joint};
    for (auto& h : x.held_joints) s.push_back(&h);
    return s;
  });
  fullarm_lcm::ident_experiment_v1_t earlier{};
  earlier.fullarm_version = "0.9";
  earlier.command_line = "fullarm identify";
  earlier.source = "sim";
  earlier.joint = "R_EB";
  earlier.sample_period_s = 0.001;
  earlier.num_held = 1;
  earlier.held_joints = {"R_SFE"};
  expectEveryBadLengthRefused(earlier, [](fullarm_lcm::ident_experiment_v1_t& x) {
    std::vector<std::string*> s = {&x.fullarm_version, &x.command_line, &x.source, &x.joint};
    for (auto& h : x.held_joints) s.push_back(&h);
    return s;
  });
}

TEST(LcmLayout, ANegativeArrayCountIsRefused) {
  const fullarm_lcm::run_header_t h = header();
  Bytes b = encode(h);
  // num_files: after the hash, three int64, five strings, seed and tick_period_us.
  std::size_t at = 8 + 24;
  for (const std::string* s : {&h.fullarm_version, &h.command_line, &h.io, &h.clock, &h.mode}) at += 4 + s->size() + 1;
  at += 12;
  ASSERT_EQ((std::uint32_t{b[at]} << 8) | b[at + 1], 2u);
  b[at] = 0xFF;  // -254 files
  EXPECT_FALSE(stringLengthsInPayload(b, &h));
  // num_parameters: after the two files (role, path, sha256 each).
  Bytes p = encode(h);
  std::size_t params = at + 2;
  for (const auto& f : h.files) params += 3 * 4 + f.role.size() + f.path.size() + f.sha256.size() + 3;
  ASSERT_EQ((std::uint32_t{p[params]} << 8) | p[params + 1], 1u);
  p[params] = 0x80;  // -32767 parameters
  EXPECT_FALSE(stringLengthsInPayload(p, &h));
  const fullarm_lcm::ident_experiment_t x = experiment();
  Bytes e = encode(x);
  std::size_t held = 8 + 8;
  for (const std::string* s : {&x.fullarm_version, &x.command_line, &x.source, &x.joint}) held += 4 + s->size() + 1;
  held += 8;
  ASSERT_EQ(e[held], 2u);
  e[held] = 0xFE;  // -2 held joints
  EXPECT_FALSE(stringLengthsInPayload(e, &x));
}

// Random damage: whatever the walk passes, the decoder takes whole and without throwing (a string
// length below 1 would make it throw, INT32_MIN crash; the sanitizer build also sees any read past
// the end).
TEST(LcmLayout, TheWalkAgreesWithTheDecoderOnDamagedMessages) {
  std::mt19937_64 rng(11);
  const auto check = [&](const auto& m) {
    using Message = std::decay_t<decltype(m)>;
    const Bytes good = encode(m);
    int passed = 0;
    for (int trial = 0; trial < 2000; ++trial) {
      Bytes b = good;
      const int flips = 1 + static_cast<int>(rng() % 3);
      for (int f = 0; f < flips; ++f) {
        b[8 + static_cast<std::size_t>(rng() % (b.size() - 8))] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      }
      Message d;
      if (!stringLengthsInPayload(b, &d)) continue;
      ++passed;
      // Passed: the hash is intact, every length and count fits, and the fields end at the end.
      int used = -1;
      EXPECT_NO_THROW(used = d.decode(b.data(), 0, static_cast<int>(b.size()))) << "trial " << trial;
      EXPECT_EQ(used, static_cast<int>(b.size())) << "trial " << trial;
    }
    EXPECT_GT(passed, 100) << "most flips land in numbers, which the walk does not read";
    Message d;
    EXPECT_TRUE(stringLengthsInPayload(good, &d));
  };
  check(header());
  check(event());
  check(experiment());
}

// Every message type in hil/lcm/ that carries a string is walked: here (lcm_layout.hpp), nested
// in one that is (run_file_t and run_parameter_t in run_header_t), or by its own decoder
// (io_node_info_t, lcm_io.cpp). A new type with a string fails this test until it is.
TEST(LcmLayout, EveryTypeWithAStringIsWalked) {
  // A field declared `string name;` or `string name[count];`: the line's first word.
  const auto declaresString = [](const std::string& line) {
    std::istringstream words(line);
    std::string first;
    return static_cast<bool>(words >> first) && first == "string";
  };
  std::set<std::string> with_strings;
  for (const auto& entry : std::filesystem::directory_iterator(arm::test::sourcePath("hil/lcm"))) {
    if (entry.path().extension() != ".lcm") continue;
    std::ifstream in(entry.path());
    for (std::string line; std::getline(in, line);) {
      if (declaresString(line)) with_strings.insert(entry.path().stem().string());
    }
  }
  const std::set<std::string> walked = {"run_header_t",       "run_file_t",         "run_parameter_t",
                                        "supervisor_event_t", "ident_experiment_t", "ident_experiment_v1_t",
                                        "io_node_info_t"};
  EXPECT_EQ(with_strings, walked);
}

}  // namespace
}  // namespace fullarm::hil
