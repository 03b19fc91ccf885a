// `fullarm run` and `fullarm replay` from the command line: a lockstep run writes its LCM log,
// summary.json and report.html with the documented keys and replays bit for bit; a real-time run
// on the simulated DTS reports its period jitter and compute time and replays bit for bit; a real board
// that is not there, a lockstep comedi run, and a corrupt log are bad input (exit 2) with a
// message that names what is wrong.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"

namespace {

using fullarm::test::runFullarm;

std::string source(const std::string& rel) {
  return std::string(FULLARM_TEST_SOURCE_DIR) + "/" + rel;
}

TEST(RunCli, ALockstepRunWritesItsLogAndSummaryAndReplaysBitForBit) {
  const auto dir = fullarm::test::cliTempDir("run_cli", "lockstep");
  const auto r = runFullarm("run --clock lockstep --duration 1 --mode hand-only --scene " +
                            source("scenes/valve_wall.yaml") + " --user " + source("config/user_reach_valve.yaml") +
                            " --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("x real time"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("missed-contact ticks: 0 of 1000"), std::string::npos) << r.output;
  ASSERT_TRUE(std::filesystem::exists(dir / "run.lcmlog"));
  ASSERT_TRUE(std::filesystem::exists(dir / "report.html"));
  nlohmann::json summary;
  std::ifstream(dir / "summary.json") >> summary;
  const nlohmann::json& results = summary["results"];
  EXPECT_EQ(results["run"]["io"], "sim");
  EXPECT_EQ(results["run"]["clock"], "lockstep");
  EXPECT_EQ(results["run"]["mode"], "hand-only");
  EXPECT_EQ(results["timing"]["ticks"], 1000);
  EXPECT_TRUE(results["timing"]["compute"].contains("p99_s"));
  EXPECT_FALSE(results["supervisor"]["tripped"]);
  EXPECT_EQ(results["oracle"]["missed_contact_ticks"], 0);
  EXPECT_EQ(results["oracle"]["links"].size(), 10u);
  EXPECT_GT(results["log"]["events"].get<int>(), 3000);

  const auto replay = runFullarm("replay " + (dir / "run.lcmlog").string() + " --out " + (dir / "replay").string());
  EXPECT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("reproduced bit for bit"), std::string::npos) << replay.output;
  nlohmann::json replay_summary;
  std::ifstream(dir / "replay" / "summary.json") >> replay_summary;
  EXPECT_EQ(replay_summary["results"]["replay"]["ticks"], 1000);
  EXPECT_EQ(replay_summary["results"]["replay"]["valve_mismatches"], 0);
}

// `--mode both` prints each run's header in the same format: the second run's header does not
// inherit the first run's fixed notation.
TEST(RunCli, BothModesPrintTheirHeadersAlike) {
  const auto dir = fullarm::test::cliTempDir("run_cli", "both");
  const auto r = runFullarm("run --clock lockstep --duration 1 --mode both --no-oracle --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("fullarm run: sim, full-arm, lockstep clock, 1 s at 1000 Hz, scene "), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("fullarm run: sim, hand-only, lockstep clock, 1 s at 1000 Hz, scene "), std::string::npos)
      << r.output;
}

// The report's data block (the JSON script element of report.html).
nlohmann::json reportData(const std::filesystem::path& html_file) {
  std::ifstream in(html_file);
  const std::string html((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string start_tag = "<script type=\"application/json\" id=\"fullarm-report-data\">";
  const std::size_t begin = html.find(start_tag);
  if (begin == std::string::npos) return {};
  const std::size_t from = begin + start_tag.size();
  return nlohmann::json::parse(html.substr(from, html.find("</script>", from) - from));
}

TEST(RunCli, TheReplaysReportShowsTheRunAsTheRunsReportDoes) {
  // A hand-only run whose hand is pulled through the truss: links penetrate.
  const auto dir = fullarm::test::cliTempDir("run_cli", "replay3d");
  const auto r = runFullarm("run --clock lockstep --duration 6 --mode hand-only --no-oracle --user " +
                            source("tests/reports/data/user_through_truss.yaml") + " --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto replay = runFullarm("replay " + (dir / "run.lcmlog").string() + " --out " + (dir / "replay").string());
  ASSERT_EQ(replay.exit_code, 0) << replay.output;
  nlohmann::json run_summary;
  nlohmann::json replay_summary;
  std::ifstream(dir / "summary.json") >> run_summary;
  std::ifstream(dir / "replay" / "summary.json") >> replay_summary;
  const nlohmann::json& shown = run_summary["results"]["replay3d"];
  EXPECT_EQ(shown["frames"], 150);
  EXPECT_NEAR(shown["frame_rate_hz"].get<double>(), 25.0, 1e-9);
  int penetrating = 0;
  for (const auto& [link, t] : shown["first_penetration_s"].items()) penetrating += t.is_null() ? 0 : 1;
  EXPECT_GT(penetrating, 0) << shown.dump();
  EXPECT_EQ(replay_summary["results"]["replay3d"], shown);
  // Read back from the log, every pose, penetration flag, torque, minimum and event is the
  // run's own, to the bit.
  const nlohmann::json from_run = reportData(dir / "report.html")["replays"]["replay-1"];
  const nlohmann::json from_log = reportData(dir / "replay" / "report.html")["replays"]["replay-1"];
  ASSERT_FALSE(from_run.is_null());
  for (const char* key : {"t_f64", "segments_f32", "penetrating_u8", "torques_f32", "minima_offsets_u32", "minima_f32",
                          "events", "links", "joints", "meshes", "torque_scale_nm", "force_scale_n"}) {
    EXPECT_EQ(from_log[key], from_run[key]) << key;
  }
}

TEST(RunCli, ARealTimeRunReportsItsTimingAndReplaysBitForBit) {
  const auto dir = fullarm::test::cliTempDir("run_cli", "realtime");
  const auto r = runFullarm("run --io sim --clock realtime --duration 1 --scene " + source("scenes/valve_wall.yaml") +
                            " --out " + dir.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("1000 ticks in"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("period jitter p50"), std::string::npos) << r.output;
  nlohmann::json summary;
  std::ifstream(dir / "summary.json") >> summary;
  const nlohmann::json& timing = summary["results"]["timing"];
  EXPECT_EQ(summary["results"]["run"]["clock"], "realtime");
  EXPECT_EQ(timing["ticks"], 1000);
  EXPECT_GT(timing["wall_s"].get<double>(), 0.9) << "the loop keeps the wall clock";
  EXPECT_GE(timing["period_jitter"]["max_s"].get<double>(), timing["period_jitter"]["p99_s"].get<double>());
  EXPECT_GT(timing["compute"]["p50_s"].get<double>(), 0.0);

  const auto replay = runFullarm("replay " + (dir / "run.lcmlog").string());
  EXPECT_EQ(replay.exit_code, 0) << replay.output;
  EXPECT_NE(replay.output.find("realtime run"), std::string::npos) << replay.output;
  EXPECT_NE(replay.output.find("reproduced bit for bit"), std::string::npos) << replay.output;
}

TEST(RunCli, BadInputExitsTwoNamingTheCause) {
  const auto dir = fullarm::test::cliTempDir("run_cli", "bad");
  const auto lockstep_comedi = runFullarm("run --io comedi --clock lockstep --duration 1 --out " + dir.string());
  EXPECT_EQ(lockstep_comedi.exit_code, 2) << lockstep_comedi.output;
  EXPECT_NE(lockstep_comedi.output.find("--clock"), std::string::npos) << lockstep_comedi.output;
  const auto no_board = runFullarm("run --io comedi --duration 1 --out " + dir.string());
  EXPECT_EQ(no_board.exit_code, 2) << no_board.output;
  EXPECT_NE(no_board.output.find("/dev/comedi0"), std::string::npos) << no_board.output;
  {
    std::ofstream junk(dir / "junk.lcmlog", std::ios::binary);
    junk << "this is not an LCM log at all, not even close to one";
  }
  const auto corrupt = runFullarm("replay " + (dir / "junk.lcmlog").string());
  EXPECT_EQ(corrupt.exit_code, 2) << corrupt.output;
  EXPECT_NE(corrupt.output.find("offset"), std::string::npos) << corrupt.output;
}

}  // namespace
