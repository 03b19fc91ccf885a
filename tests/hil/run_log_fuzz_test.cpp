// Damaged logs: truncated at every byte of its last events, single bytes flipped, random
// garbage. The reader never crashes and always gives the right verdict: a truncated log reads
// up to its last complete event and names the offset of the incomplete one; a corrupt log is a
// RunLogError naming the offset of the damaged event.

#include <gtest/gtest.h>

#include <climits>
#include <fstream>
#include <optional>
#include <random>

#include "fullarm/hil/run_log.hpp"
#include "run_log_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::hil {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes readBytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::filesystem::path& file, const Bytes& bytes, std::size_t n) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(n));
}

/// Layout of one event, worked out from the format independently of the reader under test.
struct Span {
  std::int64_t offset = 0;
  std::int64_t channel_len = 0;
  std::int64_t data_len = 0;
  [[nodiscard]] std::int64_t end() const { return offset + 28 + channel_len + data_len; }
};

std::vector<Span> layout(const Bytes& b) {
  auto be32 = [&](std::size_t at) {
    return static_cast<std::int64_t>((std::uint32_t{b[at]} << 24) | (std::uint32_t{b[at + 1]} << 16) |
                                     (std::uint32_t{b[at + 2]} << 8) | std::uint32_t{b[at + 3]});
  };
  std::vector<Span> spans;
  std::size_t at = 0;
  while (at < b.size()) {
    Span s{static_cast<std::int64_t>(at), be32(at + 20), be32(at + 24)};
    spans.push_back(s);
    at = static_cast<std::size_t>(s.end());
  }
  return spans;
}

/// The reader's verdict on a file.
struct Verdict {
  std::vector<LcmLogEvent> events;  ///< complete events read (before an error)
  bool truncated = false;
  std::int64_t truncated_offset = -1;
  std::string warning;
  std::optional<RunLogError> error;
};

Verdict readAll(const std::filesystem::path& file) {
  Verdict v;
  try {
    RunLogReader reader(file);
    RunLogEntry entry;
    while (reader.next(entry)) v.events.push_back(entry.event);
    v.truncated = reader.truncated();
    v.truncated_offset = reader.truncatedOffset();
    v.warning = reader.warning();
  } catch (const RunLogError& e) {
    v.error = e;
  }
  return v;
}

class RunLogFuzz : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fullarm::test::scratchDir("hil_run_log_fuzz");
    const auto file = dir_ / "clean.lcmlog";
    test::writeSampleLog(file, 40);
    clean_ = readBytes(file);
    spans_ = layout(clean_);
    const Verdict v = readAll(file);
    ASSERT_FALSE(v.error.has_value());
    original_ = v.events;
    ASSERT_EQ(original_.size(), spans_.size());
    damaged_ = dir_ / "damaged.lcmlog";
  }

  void expectPrefixIntact(const Verdict& v, std::size_t n) const {
    ASSERT_GE(v.events.size(), n);
    for (std::size_t i = 0; i < n; ++i) {
      EXPECT_EQ(v.events[i].channel, original_[i].channel);
      EXPECT_EQ(v.events[i].data, original_[i].data);
      EXPECT_EQ(v.events[i].utime_us, original_[i].utime_us);
    }
  }

  std::filesystem::path dir_;
  std::filesystem::path damaged_;
  Bytes clean_;
  std::vector<Span> spans_;
  std::vector<LcmLogEvent> original_;
};

TEST_F(RunLogFuzz, TruncatedAtEveryByteOfTheLastEvents) {
  const std::size_t first = spans_.size() - 4;  // the last four events, the minima fragments among them
  for (std::size_t k = first; k < spans_.size(); ++k) {
    for (std::int64_t cut = spans_[k].offset; cut < spans_[k].end(); ++cut) {
      writeBytes(damaged_, clean_, static_cast<std::size_t>(cut));
      const Verdict v = readAll(damaged_);
      ASSERT_FALSE(v.error.has_value()) << "cut at " << cut << ": " << v.error->what();
      EXPECT_EQ(v.events.size(), k) << "cut at " << cut;
      expectPrefixIntact(v, k);
      if (cut == spans_[k].offset) {
        EXPECT_FALSE(v.truncated) << "cut at an event boundary " << cut;
      } else {
        EXPECT_TRUE(v.truncated) << "cut at " << cut;
        EXPECT_EQ(v.truncated_offset, spans_[k].offset) << "cut at " << cut;
        EXPECT_NE(v.warning.find("byte offset " + std::to_string(spans_[k].offset)), std::string::npos) << v.warning;
      }
    }
  }
}

TEST_F(RunLogFuzz, EveryByteFlippedInHeadersChannelsAndPayloads) {
  // Each byte of the first, a middle and the last event, inverted. Where the flip lands decides
  // the verdict (worked out here from the layout).
  const std::vector<std::size_t> chosen = {0, 1, spans_.size() / 2, spans_.size() - 1};
  for (const std::size_t k : chosen) {
    const Span& s = spans_[k];
    const bool last = k + 1 == spans_.size();
    for (std::int64_t p = s.offset; p < s.end(); ++p) {
      Bytes bytes = clean_;
      bytes[static_cast<std::size_t>(p)] ^= 0xFF;
      writeBytes(damaged_, bytes, bytes.size());
      const Verdict v = readAll(damaged_);
      const std::int64_t rel = p - s.offset;
      SCOPED_TRACE("event " + std::to_string(k) + ", byte " + std::to_string(rel));
      expectPrefixIntact(v, k);  // everything before the damaged event reads as it was
      if (v.error) {
        EXPECT_GE(v.error->offset(), s.offset);
        EXPECT_NE(std::string(v.error->what()).find("byte offset " + std::to_string(v.error->offset())),
                  std::string::npos);
      }
      if (rel < 4) {  // sync word
        ASSERT_TRUE(v.error.has_value());
        EXPECT_EQ(v.error->offset(), s.offset);
      } else if (rel < 12) {  // event number: out of order at this event or the next one
        if (v.error) {
          EXPECT_TRUE(v.error->offset() == s.offset || (!last && v.error->offset() == spans_[k + 1].offset));
        } else {
          EXPECT_FALSE(v.truncated);
          EXPECT_EQ(v.events.size(), original_.size());
        }
      } else if (rel < 20) {  // timestamp: no check can see it; only that event's time differs
        ASSERT_FALSE(v.error.has_value()) << v.error->what();
        ASSERT_EQ(v.events.size(), original_.size());
        EXPECT_NE(v.events[k].utime_us, original_[k].utime_us);
        EXPECT_EQ(v.events[k].data, original_[k].data);
      } else if (rel < 28) {  // channel and data lengths
        if (!v.error) {
          // Only a length that runs past the end of the file can pass for a truncated last event.
          EXPECT_TRUE(last && v.truncated) << "a damaged length went unnoticed";
          EXPECT_EQ(v.truncated_offset, s.offset);
        }
      } else if (rel < 28 + s.channel_len) {  // channel name: no longer text
        ASSERT_TRUE(v.error.has_value());
        EXPECT_EQ(v.error->offset(), s.offset);
      } else if (rel < 28 + s.channel_len + 8) {  // the type's hash: does not decode
        ASSERT_TRUE(v.error.has_value());
        EXPECT_EQ(v.error->offset(), s.offset);
        EXPECT_EQ(v.error->channel(), original_[k].channel);
      } else {  // a payload value: undecodable, or (no checksum in LCM) a changed value
        if (v.error) {
          EXPECT_EQ(v.error->offset(), s.offset);
          EXPECT_EQ(v.error->channel(), original_[k].channel);
        } else {
          EXPECT_FALSE(v.truncated);
          ASSERT_EQ(v.events.size(), original_.size());
          EXPECT_NE(v.events[k].data, original_[k].data);
        }
      }
    }
  }
}

// The run header's strings carry their own int32 length (with the terminating NUL): a length of
// zero or below, or past the payload's end, is a corrupt header naming its offset, never a string
// read out of bounds or an exception of the standard library's.
TEST_F(RunLogFuzz, AHeaderStringLengthOutOfRangeIsCorruptNamingTheHeader) {
  std::size_t header = spans_.size();
  for (std::size_t k = 0; k < spans_.size(); ++k) {
    if (original_[k].channel == channel::kRunHeader) header = k;
  }
  ASSERT_LT(header, spans_.size());
  const Span& h = spans_[header];
  // The payload: the type's hash (8 bytes), utime, seq and wall_utime (8 each), then the first
  // string's length.
  const auto at = static_cast<std::size_t>(h.offset + 28 + h.channel_len + 8 + 24);
  for (const std::int64_t len :
       {std::int64_t{0}, std::int64_t{-1}, std::int64_t{INT32_MIN}, std::int64_t{INT32_MAX}, h.data_len - 31}) {
    SCOPED_TRACE("length " + std::to_string(len));
    Bytes bytes = clean_;
    const auto u = static_cast<std::uint32_t>(static_cast<std::int32_t>(len));
    bytes[at] = static_cast<std::uint8_t>(u >> 24);
    bytes[at + 1] = static_cast<std::uint8_t>(u >> 16);
    bytes[at + 2] = static_cast<std::uint8_t>(u >> 8);
    bytes[at + 3] = static_cast<std::uint8_t>(u);
    writeBytes(damaged_, bytes, bytes.size());
    const Verdict v = readAll(damaged_);
    ASSERT_TRUE(v.error.has_value()) << "a damaged string length went unnoticed";
    EXPECT_EQ(v.error->offset(), h.offset);
    EXPECT_EQ(v.error->channel(), channel::kRunHeader);
    expectPrefixIntact(v, header);
  }
}

TEST_F(RunLogFuzz, RandomBitFlipsAnywhereNeverCrash) {
  std::mt19937_64 rng(2024);
  for (int trial = 0; trial < 400; ++trial) {
    Bytes bytes = clean_;
    const int flips = 1 + static_cast<int>(rng() % 4);
    std::size_t first = bytes.size();
    for (int f = 0; f < flips; ++f) {
      const std::size_t p = static_cast<std::size_t>(rng() % bytes.size());
      bytes[p] ^= static_cast<std::uint8_t>(1u << (rng() % 8));
      first = std::min(first, p);
    }
    writeBytes(damaged_, bytes, bytes.size());
    const Verdict v = readAll(damaged_);
    std::size_t before = 0;
    while (before < spans_.size() && spans_[before].end() <= static_cast<std::int64_t>(first)) ++before;
    // The reader is sequential: every event before the first damaged one reads as it was, and
    // any verdict is about that event or a later one.
    expectPrefixIntact(v, before);
    if (before < spans_.size()) {
      if (v.error) {
        EXPECT_GE(v.error->offset(), spans_[before].offset);
      }
      if (v.truncated) {
        EXPECT_GE(v.truncated_offset, spans_[before].offset);
      }
    }
  }
}

TEST_F(RunLogFuzz, RandomGarbageIsCorruptOrEmpty) {
  std::mt19937_64 rng(99);
  for (int trial = 0; trial < 300; ++trial) {
    Bytes garbage(static_cast<std::size_t>(rng() % 3000));
    for (auto& b : garbage) b = static_cast<std::uint8_t>(rng());
    if (trial % 3 == 1 && garbage.size() >= 4) {  // a valid sync word in front
      garbage[0] = 0xED;
      garbage[1] = 0xA1;
      garbage[2] = 0xDA;
      garbage[3] = 0x01;
    }
    writeBytes(damaged_, garbage, garbage.size());
    const Verdict v = readAll(damaged_);
    if (garbage.empty()) {
      EXPECT_FALSE(v.error.has_value());
      EXPECT_TRUE(v.events.empty());
      continue;
    }
    // Random bytes never make a complete run-log event; the verdict is about offset 0.
    EXPECT_TRUE(v.events.empty()) << trial;
    EXPECT_TRUE(v.error.has_value() || v.truncated) << trial;
    if (v.error) {
      EXPECT_EQ(v.error->offset(), 0) << trial;
    }
    if (v.truncated) {
      EXPECT_EQ(v.truncated_offset, 0) << trial;
    }
  }
}

TEST_F(RunLogFuzz, GarbageAfterAGoodLogIsCorruptAtItsStart) {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 100; ++trial) {
    Bytes bytes = clean_;
    const std::size_t n = 1 + static_cast<std::size_t>(rng() % 200);
    for (std::size_t i = 0; i < n; ++i) bytes.push_back(static_cast<std::uint8_t>(rng()));
    if (bytes[clean_.size()] == 0xED) bytes[clean_.size()] = 0x00;  // not a sync byte
    writeBytes(damaged_, bytes, bytes.size());
    const Verdict v = readAll(damaged_);
    ASSERT_TRUE(v.error.has_value()) << trial;
    EXPECT_EQ(v.error->offset(), static_cast<std::int64_t>(clean_.size()));
    expectPrefixIntact(v, original_.size());
  }
}

}  // namespace
}  // namespace fullarm::hil
