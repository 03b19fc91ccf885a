#include "fullarm/hil/run_log.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <thread>

#include "run_log_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::hil {
namespace {

using test::SampleRun;
using test::writeSampleLog;

/// Every event of a log as lcm::LogFile reads it (LCM's own reader, independent of ours).
std::vector<LcmLogEvent> readWithLcm(const std::filesystem::path& file) {
  lcm::LogFile log(file.string(), "r");
  EXPECT_TRUE(log.good());
  std::vector<LcmLogEvent> events;
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    LcmLogEvent out;
    out.event_number = e->eventnum;
    out.utime_us = e->timestamp;
    out.channel = e->channel;
    const auto* p = static_cast<const std::uint8_t*>(e->data);
    out.data.assign(p, p + e->datalen);
    events.push_back(std::move(out));
  }
  return events;
}

std::vector<LcmLogEvent> readWithOurs(const std::filesystem::path& file, bool* truncated = nullptr) {
  LcmLogReader reader(file);
  std::vector<LcmLogEvent> events;
  LcmLogEvent e;
  while (reader.next(e)) events.push_back(e);
  if (truncated != nullptr) *truncated = reader.truncated();
  return events;
}

TEST(RunLog, WriterThreadLogsEveryRecordAndLcmReadsTheSameEvents) {
  const auto dir = fullarm::test::scratchDir("hil_run_log_roundtrip");
  const auto file = dir / "run.lcmlog";
  const SampleRun run = writeSampleLog(file, 2000);
  ASSERT_EQ(run.stats.records_dropped, 0u);
  EXPECT_EQ(run.stats.write_errors + run.stats.encode_errors, 0u);

  // LCM's own reader and ours agree event by event.
  const std::vector<LcmLogEvent> lcm_events = readWithLcm(file);
  bool truncated = true;
  const std::vector<LcmLogEvent> ours = readWithOurs(file, &truncated);
  EXPECT_FALSE(truncated);
  ASSERT_EQ(ours.size(), lcm_events.size());
  std::int64_t offset = 0;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    EXPECT_EQ(ours[i].event_number, lcm_events[i].event_number);
    EXPECT_EQ(ours[i].utime_us, lcm_events[i].utime_us);
    EXPECT_EQ(ours[i].channel, lcm_events[i].channel);
    EXPECT_EQ(ours[i].data, lcm_events[i].data);
    EXPECT_EQ(ours[i].offset, offset);
    offset += kLcmEventHeaderBytes + static_cast<std::int64_t>(ours[i].channel.size() + ours[i].data.size());
  }
  EXPECT_EQ(offset, static_cast<std::int64_t>(std::filesystem::file_size(file)));

  // Decoded by channel, the log holds exactly what was pushed, in order per channel.
  RunLogReader reader(file);
  RunLogEntry entry;
  std::vector<JointStateRecord> joints;
  std::vector<HapticStatusRecord> haptics;
  std::vector<SupervisorEventRecord> events;
  std::vector<MinimaSetRecord> sets;
  MinimaSetAssembler assembler;
  int headers = 0;
  while (reader.next(entry)) {
    if (const auto* m = std::get_if<fullarm_lcm::joint_state_t>(&entry.message)) joints.push_back(fromMessage(*m));
    if (const auto* m = std::get_if<fullarm_lcm::haptic_status_t>(&entry.message)) haptics.push_back(fromMessage(*m));
    if (const auto* m = std::get_if<fullarm_lcm::supervisor_event_t>(&entry.message)) events.push_back(fromMessage(*m));
    if (const auto* m = std::get_if<fullarm_lcm::minima_set_t>(&entry.message)) {
      if (assembler.add(*m)) sets.push_back(assembler.set());
    }
    if (const auto* m = std::get_if<fullarm_lcm::run_header_t>(&entry.message)) {
      ++headers;
      EXPECT_EQ(m->seed, 7);
      EXPECT_EQ(m->files.at(0).path, "scenes/valve_wall.yaml");
      EXPECT_EQ(m->parameters.at(0).key, "duration_s");
    }
  }
  EXPECT_FALSE(reader.truncated());
  EXPECT_EQ(headers, 1);
  ASSERT_EQ(joints.size(), run.joints.size());
  for (std::size_t i = 0; i < joints.size(); ++i) {
    EXPECT_EQ(joints[i].tick, run.joints[i].tick);
    EXPECT_EQ(joints[i].q_rad, run.joints[i].q_rad);
    EXPECT_EQ(joints[i].tau_measured_nm, run.joints[i].tau_measured_nm);
    EXPECT_EQ(joints[i].valve_command_v, run.joints[i].valve_command_v);
  }
  ASSERT_EQ(haptics.size(), run.haptics.size());
  for (std::size_t i = 0; i < haptics.size(); ++i) {
    EXPECT_EQ(haptics[i].tau_contact_nm, run.haptics[i].tau_contact_nm);
    EXPECT_EQ(haptics[i].links[6].force_world_n, run.haptics[i].links[6].force_world_n);
  }
  ASSERT_EQ(sets.size(), run.minima.size());
  for (std::size_t i = 0; i < sets.size(); ++i) {
    EXPECT_EQ(sets[i].set_id, run.minima[i].set_id);
    EXPECT_EQ(sets[i].adopted_tick, run.minima[i].adopted_tick);
    EXPECT_EQ(sets[i].num_minima, run.minima[i].num_minima);
    EXPECT_EQ(sets[i].minima[24].tri_object, 48);
    EXPECT_TRUE(std::isnan(sets[i].minima[24].previous_distance_m));
  }
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].messageView(), "joint 4 velocity beyond its limit");
}

TEST(RunLog, WriterStatsCountEventsAndRingDrops) {
  const auto dir = fullarm::test::scratchDir("hil_run_log_stats");
  SpscRing<JointStateRecord> ring(4);
  RunLogWriter writer({dir / "drops.lcmlog"});
  writer.addSource(ring, channel::kJointState);
  for (int i = 0; i < 10; ++i) ring.tryPush(test::sampleJointState(i));  // 6 refused: no thread drains
  EXPECT_EQ(writer.drainOnce(), 4u);
  writer.stop();
  const RunLogStats stats = writer.stats();
  EXPECT_EQ(stats.events_written, 4u);
  EXPECT_EQ(stats.records_dropped, 6u);
  EXPECT_EQ(stats.write_errors, 0u);
  EXPECT_GE(stats.flushes, 1u);
  EXPECT_EQ(readWithLcm(dir / "drops.lcmlog").size(), 4u);
}

TEST(RunLog, WriterRefusesAFileItCannotCreate) {
  const auto dir = fullarm::test::scratchDir("hil_run_log_nofile");
  const auto file = dir / "missing_folder" / "run.lcmlog";
  try {
    RunLogWriter writer({file});
    FAIL() << "no error";
  } catch (const RunLogError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(LcmLogReader{file}, RunLogError);
}

// lcm-logplayer, LCM's own tool, plays the whole log onto a file:// LCM URL: every event
// arrives with its channel and payload.
#ifdef FULLARM_LCM_LOGPLAYER
TEST(RunLog, LcmLogplayerPlaysTheWholeLog) {
  const auto dir = fullarm::test::scratchDir("hil_run_log_logplayer");
  const auto file = dir / "run.lcmlog";
  const auto played = dir / "played.lcmlog";
  writeSampleLog(file, 300);
  const std::string command = std::string(FULLARM_LCM_LOGPLAYER) + " -s 0 -l 'file://" + played.string() +
                              "?mode=w' '" + file.string() + "' > '" + (dir / "out.txt").string() + "' 2>&1";
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const std::vector<LcmLogEvent> original = readWithLcm(file);
  const std::vector<LcmLogEvent> replayed = readWithLcm(played);
  ASSERT_EQ(replayed.size(), original.size());
  for (std::size_t i = 0; i < original.size(); ++i) {
    EXPECT_EQ(replayed[i].channel, original[i].channel);
    EXPECT_EQ(replayed[i].data, original[i].data);
  }
}
#endif

// A run killed (SIGKILL) while it logs: what the writer flushed is on disk; the reader's
// verdict is a complete or a truncated log, never a corrupt one.
#if !defined(__SANITIZE_THREAD__)
constexpr bool kForkTests = true;
#else
constexpr bool kForkTests = false;  // ThreadSanitizer does not support threads in a forked child
#endif

TEST(RunLog, FlushedEventsSurviveAKill) {
  if (!kForkTests) GTEST_SKIP() << "fork-based test skipped under ThreadSanitizer";
  const auto dir = fullarm::test::scratchDir("hil_run_log_kill");
  const auto file = dir / "killed.lcmlog";
  constexpr int kRecords = 500;
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    SpscRing<JointStateRecord> ring(1024);
    RunLogWriter writer({file, std::chrono::milliseconds(1), std::chrono::milliseconds(5)});
    writer.addSource(ring, channel::kJointState);
    writer.start();
    for (int i = 0; i < kRecords; ++i) ring.tryPush(test::sampleJointState(i));
    // Wait until every record is written and a flush came after the last one, then die.
    while (writer.stats().events_written < kRecords) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    const std::uint64_t flushes = writer.stats().flushes;
    while (writer.stats().flushes < flushes + 2) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    ::kill(::getpid(), SIGKILL);
    ::_exit(3);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status));
  EXPECT_EQ(WTERMSIG(status), SIGKILL);
  RunLogReader reader(file);
  RunLogEntry entry;
  int n = 0;
  while (reader.next(entry)) ++n;
  EXPECT_EQ(n, kRecords);
  EXPECT_FALSE(reader.truncated());
}

TEST(RunLog, KilledMidRunGivesACompleteOrTruncatedLog) {
  if (!kForkTests) GTEST_SKIP() << "fork-based test skipped under ThreadSanitizer";
  const auto dir = fullarm::test::scratchDir("hil_run_log_midkill");
  for (int attempt = 0; attempt < 3; ++attempt) {
    const auto file = dir / ("killed_" + std::to_string(attempt) + ".lcmlog");
    int ready[2];
    ASSERT_EQ(::pipe(ready), 0);
    const pid_t child = ::fork();
    ASSERT_GE(child, 0);
    if (child == 0) {
      ::close(ready[0]);
      SpscRing<HapticStatusRecord> ring(1024);
      RunLogWriter writer({file, std::chrono::milliseconds(1), std::chrono::milliseconds(3)});
      writer.addSource(ring, channel::kHapticStatus);
      writer.start();
      for (std::int64_t tick = 0;; ++tick) {
        ring.tryPush(test::sampleHapticStatus(tick));
        if (tick == 200 && ::write(ready[1], "x", 1) != 1) ::_exit(4);
        std::this_thread::sleep_for(std::chrono::microseconds(50));
      }
    }
    ::close(ready[1]);
    char c = 0;
    ASSERT_EQ(::read(ready[0], &c, 1), 1);
    ::close(ready[0]);
    std::this_thread::sleep_for(std::chrono::milliseconds(5 + 7 * attempt));
    ::kill(child, SIGKILL);
    int status = 0;
    ASSERT_EQ(::waitpid(child, &status, 0), child);
    RunLogReader reader(file);
    RunLogEntry entry;
    std::int64_t last_tick = -1;
    EXPECT_NO_THROW({
      while (reader.next(entry)) {
        const auto& m = std::get<fullarm_lcm::haptic_status_t>(entry.message);
        EXPECT_GT(m.tick, last_tick);  // in order (a ring drop under load may leave a gap)
        last_tick = m.tick;
      }
    });
    EXPECT_GE(last_tick, 0);
    if (reader.truncated()) {
      EXPECT_NE(reader.warning().find("byte offset " + std::to_string(reader.truncatedOffset())), std::string::npos)
          << reader.warning();
    }
  }
}

TEST(RunLog, UnknownChannelIsAnErrorUnlessSkipped) {
  const auto dir = fullarm::test::scratchDir("hil_run_log_unknown");
  const auto file = dir / "other.lcmlog";
  {
    RunLogWriter writer({file});
    writer.writeMessage(channel::kJointState, 1, toMessage(test::sampleJointState(1)));
    writer.writeMessage("SOMEONE_ELSE", 2, toMessage(test::sampleJointState(2)));
    writer.writeMessage(channel::kJointState, 3, toMessage(test::sampleJointState(3)));
  }
  RunLogEntry entry;
  {
    RunLogReader reader(file);
    ASSERT_TRUE(reader.next(entry));
    try {
      reader.next(entry);
      FAIL() << "no error";
    } catch (const RunLogError& e) {
      EXPECT_EQ(e.channel(), "SOMEONE_ELSE");
      EXPECT_GT(e.offset(), 0);
      EXPECT_NE(std::string(e.what()).find("byte offset " + std::to_string(e.offset())), std::string::npos);
    }
  }
  RunLogReader reader(file, {.skip_unknown_channels = true});
  int n = 0;
  while (reader.next(entry)) ++n;
  EXPECT_EQ(n, 2);
  EXPECT_EQ(reader.skipped(), 1);
}

TEST(RunLog, APayloadOfTheWrongTypeIsAnErrorNamingOffsetAndChannel) {
  const auto dir = fullarm::test::scratchDir("hil_run_log_wrongtype");
  const auto file = dir / "wrong.lcmlog";
  {
    RunLogWriter writer({file});
    writer.writeMessage(channel::kJointState, 1, toMessage(test::sampleJointState(1)));
    writer.writeMessage(channel::kHapticStatus, 2, toMessage(test::sampleJointState(2)));
  }
  RunLogReader reader(file);
  RunLogEntry entry;
  ASSERT_TRUE(reader.next(entry));
  const std::int64_t second = kLcmEventHeaderBytes + static_cast<std::int64_t>(entry.event.channel.size() + entry.event.data.size());
  try {
    reader.next(entry);
    FAIL() << "no error";
  } catch (const RunLogError& e) {
    EXPECT_EQ(e.offset(), second);
    EXPECT_EQ(e.channel(), channel::kHapticStatus);
    EXPECT_NE(std::string(e.what()).find("haptic_status_t"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fullarm::hil
