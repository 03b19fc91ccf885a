// The run's LCM log: SHA-256 of the header's inputs (FIPS 180-4 vectors), a lockstep run's log
// replayed through the same tick bit for bit, a truncated log replayed up to its last complete
// event with a warning naming the offset, a corrupt one rejected naming the offset.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "fullarm/hil/run_recording.hpp"
#include "run_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::hil {
namespace {

TEST(Sha256, MatchesTheStandardVectors) {
  EXPECT_EQ(sha256Hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256Hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256Hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

std::filesystem::path recordedLog() {
  static const std::filesystem::path log = [] {
    const auto dir = fullarm::test::scratchDir("hil_recording");
    RunOptions o = test::shippedRun(2.0);
    o.oracle = false;
    o.log = dir / "run.lcmlog";
    o.command_line = "fullarm run --duration 2";
    const RunResult r = runHil(o);
    EXPECT_GT(r.log_events, 2000u * 3);
    EXPECT_EQ(r.log_records_dropped, 0u);
    return o.log;
  }();
  return log;
}

TEST(RunLog, ALockstepRunReplaysBitForBit) {
  const ReplayReport report = replayLog(recordedLog());
  EXPECT_EQ(report.ticks, 2000u);
  EXPECT_GT(report.sets, 150u);
  EXPECT_TRUE(report.identical()) << report.first_mismatch;
  EXPECT_FALSE(report.truncated);
  EXPECT_TRUE(report.changed_files.empty());
  EXPECT_EQ(report.clock, "lockstep");
}

TEST(RunLog, ATruncatedLogReplaysUpToItsLastCompleteEventWithAWarning) {
  const auto dir = fullarm::test::scratchDir("hil_truncated");
  const auto cut = dir / "cut.lcmlog";
  std::filesystem::copy_file(recordedLog(), cut);
  const auto size = std::filesystem::file_size(cut);
  std::filesystem::resize_file(cut, size / 2 + 7);  // a crash in the middle of an event
  const ReplayReport report = replayLog(cut);
  EXPECT_TRUE(report.truncated);
  EXPECT_NE(report.warning.find("offset"), std::string::npos) << report.warning;
  EXPECT_GT(report.ticks, 500u);
  EXPECT_LT(report.ticks, 2000u);
  EXPECT_TRUE(report.identical()) << report.first_mismatch;
}

TEST(RunLog, ACorruptLogIsAnErrorNamingTheOffset) {
  const auto dir = fullarm::test::scratchDir("hil_corrupt");
  const auto bad = dir / "bad.lcmlog";
  std::filesystem::copy_file(recordedLog(), bad);
  {
    std::fstream f(bad, std::ios::in | std::ios::out | std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    // Break the sync word of an event in the middle of the log.
    const std::string sync("\xED\xA1\xDA\x01", 4);
    const std::size_t at = bytes.find(sync, bytes.size() / 2);
    ASSERT_NE(at, std::string::npos);
    f.seekp(static_cast<std::streamoff>(at));
    f.write("XXXX", 4);
  }
  try {
    (void)replayLog(bad);
    FAIL() << "a corrupt log must be an error";
  } catch (const RunLogError& e) {
    EXPECT_NE(std::string(e.what()).find("offset"), std::string::npos) << e.what();
    EXPECT_GE(e.offset(), 0);
  }
}

}  // namespace
}  // namespace fullarm::hil
