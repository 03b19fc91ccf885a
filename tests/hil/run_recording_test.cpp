// The run's LCM log: SHA-256 of the header's inputs (FIPS 180-4 vectors), a lockstep run's log
// replayed through the same tick bit for bit, a truncated log replayed up to its last complete
// event with a warning naming the offset, a corrupt one rejected naming the offset, a header
// parameter that does not read as its kind rejected naming it, a run that cannot configure its
// device leaving an empty log.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "fullarm/core/config_error.hpp"
#include "fullarm/hil/run_log.hpp"

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

// A run whose device cannot be configured (the real board, in real time, on a machine without
// one) writes no header and no tick, and leaves no earlier run's log under its name: the file is
// created empty.
TEST(RunLog, ARunThatCannotConfigureItsDeviceLeavesAnEmptyLogNotAnEarlierOne) {
  const auto dir = fullarm::test::scratchDir("hil_no_board_log");
  RunOptions o = test::shippedRun(1.0);
  o.io = IoKind::kComedi;
  o.clock = ClockKind::kRealtime;
  o.log = dir / "run.lcmlog";
  // The shipped channel map with a device file that exists nowhere, so that a machine with the
  // board does not move the arm here.
  {
    std::ifstream in(arm::test::sourcePath("config/dts_daq.yaml"));
    std::ostringstream text;
    text << in.rdbuf();
    std::string map = text.str();
    const std::string shipped = "device: /dev/comedi0";
    const std::size_t at = map.find(shipped);
    ASSERT_NE(at, std::string::npos);
    map.replace(at, shipped.size(), "device: " + (dir / "no_such_board").string());
    std::ofstream(dir / "daq.yaml") << map;
    o.daq_config = dir / "daq.yaml";
  }
  std::filesystem::copy_file(recordedLog(), o.log, std::filesystem::copy_options::overwrite_existing);
  ASSERT_GT(std::filesystem::file_size(o.log), 0u);
  try {
    (void)runHil(o);
    FAIL() << "no board: the run must not start";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open the Comedi device"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("no_such_board"), std::string::npos) << e.what();
  }
  ASSERT_TRUE(std::filesystem::exists(o.log));
  EXPECT_EQ(std::filesystem::file_size(o.log), 0u);
}

// The recorded log with one header parameter's value replaced, every other event as it was.
std::filesystem::path logWithHeaderParameter(const std::filesystem::path& dir, const std::string& key,
                                             const std::string& value) {
  const auto out = dir / (key + ".lcmlog");
  RunLogWriterOptions options;
  options.file = out;
  RunLogWriter writer(options);
  RunLogReader reader(recordedLog());
  RunLogEntry entry;
  bool replaced = false;
  while (reader.next(entry)) {
    if (auto* h = std::get_if<fullarm_lcm::run_header_t>(&entry.message)) {
      for (fullarm_lcm::run_parameter_t& p : h->parameters) {
        if (p.key == key) {
          p.value = value;
          replaced = true;
        }
      }
    }
    std::visit([&](const auto& m) { writer.writeMessage(entry.event.channel, entry.event.utime_us, m); },
               entry.message);
  }
  EXPECT_TRUE(replaced) << key;
  return out;
}

// A header whose numbers do not read as their kind is an error naming the log and the parameter,
// not an exception from the standard library's parsers nor a run with another setting.
TEST(RunLog, AHeaderParameterThatIsNotItsKindIsAnErrorNamingIt) {
  const auto dir = fullarm::test::scratchDir("hil_bad_header");
  const std::vector<std::pair<std::string, std::string>> bad = {{"duration_s", "abc"},
                                                                {"duration_s", "nan"},
                                                                {"duration_s", "inf"},
                                                                {"duration_s", "-2"},
                                                                {"duration_s", "0"},
                                                                {"duration_s", "2 s"},
                                                                {"duration_s", ""},
                                                                {"global_period_ticks", "1.5"},
                                                                {"global_period_ticks", "0"},
                                                                {"global_period_ticks", "99999999999"},
                                                                {"delivery_delay_ticks", "x"},
                                                                {"delivery_delay_ticks", "-1"}};
  for (const auto& [key, value] : bad) {
    SCOPED_TRACE(key + " = '" + value + "'");
    const auto log = logWithHeaderParameter(dir, key, value);
    try {
      (void)replayLog(log);
      FAIL() << "a bad header value must be an error";
    } catch (const core::ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find(log.string()), std::string::npos) << what;
      EXPECT_NE(what.find("run header parameter " + key), std::string::npos) << what;
      EXPECT_NE(what.find("'" + value + "'"), std::string::npos) << what;
    }
  }
  // The same rewriting with the recorded values replays bit for bit: the errors come from the
  // values alone.
  const ReplayReport report = replayLog(logWithHeaderParameter(dir, "duration_s", "2"));
  EXPECT_TRUE(report.identical()) << report.first_mismatch;
  EXPECT_EQ(report.ticks, 2000u);
}

}  // namespace
}  // namespace fullarm::hil
