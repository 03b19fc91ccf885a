// core::Progress against hand-computed lines: a fake clock fixes the elapsed times, so every
// estimate of the time left is elapsed / done * (total - done) worked out by hand.

#include "fullarm/core/progress.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "fullarm/core/job_pool.hpp"

namespace fullarm::core {
namespace {

std::vector<std::string> lines(const std::string& text) {
  std::vector<std::string> out;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

TEST(ProgressTest, FormatsDurationsForPeople) {
  EXPECT_EQ(formatDuration(0.0), "0 s");
  EXPECT_EQ(formatDuration(-3.0), "0 s");
  EXPECT_EQ(formatDuration(8.4), "8 s");
  EXPECT_EQ(formatDuration(59.4), "59 s");
  EXPECT_EQ(formatDuration(125.0), "2 min 05 s");
  EXPECT_EQ(formatDuration(3720.0), "1 h 02 min");
  EXPECT_EQ(formatDuration(std::numeric_limits<double>::quiet_NaN()), "0 s");
}

TEST(ProgressTest, LinesNameEachStepWithElapsedAndTimeLeft) {
  double now_s = 100.0;
  std::ostringstream out;
  {
    Progress progress(out, ProgressMode::kLines, [&] { return now_s; });
    progress.begin("tune", 4);
    now_s = 110.0;
    progress.step("SFE: linear stage");
    now_s = 130.0;
    progress.step("SFE: nonlinear stage");
    now_s = 160.0;
    progress.step("EB: linear stage");
    now_s = 170.0;
    progress.step("EB: nonlinear stage");
    progress.end("2 of 2 verified");
  }
  EXPECT_EQ(lines(out.str()), (std::vector<std::string>{
                                  "tune [0/4] (0 s elapsed)",
                                  // 10 s for 1 of 4: 30 s for the other 3.
                                  "tune [1/4] SFE: linear stage (10 s elapsed, about 30 s left)",
                                  "tune [2/4] SFE: nonlinear stage (30 s elapsed, about 30 s left)",
                                  "tune [3/4] EB: linear stage (1 min 00 s elapsed, about 20 s left)",
                                  "tune [4/4] EB: nonlinear stage (1 min 10 s elapsed)",
                                  "tune: done in 1 min 10 s: 2 of 2 verified",
                              }));
  EXPECT_EQ(out.str().find('\r'), std::string::npos);
}

TEST(ProgressTest, UnnamedUnitsGiveALinePerTwentiethInLineMode) {
  double now_s = 0.0;
  std::ostringstream out;
  Progress progress(out, ProgressMode::kLines, [&] { return now_s; });
  progress.begin("validate: Monte-Carlo", 200);
  for (int i = 0; i < 200; ++i) {
    now_s += 0.5;
    progress.advance();
  }
  progress.end();
  const std::vector<std::string> printed = lines(out.str());
  // The begin line, 20 lines at 10, 20, ..., 200 runs (5 s apart), the end line.
  ASSERT_EQ(printed.size(), 22U);
  EXPECT_EQ(printed[1], "validate: Monte-Carlo [10/200] (5 s elapsed, about 1 min 35 s left)");
  EXPECT_EQ(printed[20], "validate: Monte-Carlo [200/200] (1 min 40 s elapsed)");
  EXPECT_EQ(printed[21], "validate: Monte-Carlo: done in 1 min 40 s");
  EXPECT_EQ(progress.done(), 200U);
}

TEST(ProgressTest, QuickUnitsPrintNoCloserThanTwoSeconds) {
  double now_s = 0.0;
  std::ostringstream out;
  Progress progress(out, ProgressMode::kLines, [&] { return now_s; });
  progress.begin("plant simulate", 2000);
  for (int i = 0; i < 2000; ++i) {
    now_s += 0.003;  // 6 s in all, a twentieth every 0.3 s
    progress.advance();
  }
  progress.end();
  const std::vector<std::string> printed = lines(out.str());
  // The begin line, one line each 2 s (at 2.1 s and 4.2 s: the first twentieth boundary after
  // the interval), the end line.
  ASSERT_EQ(printed.size(), 4U) << out.str();
  EXPECT_EQ(printed[1], "plant simulate [700/2000] (2 s elapsed, about 4 s left)");
  EXPECT_EQ(printed[3], "plant simulate: done in 6 s");
}

TEST(ProgressTest, BarRedrawsOneLineInPlace) {
  double now_s = 0.0;
  std::ostringstream out;
  {
    Progress progress(out, ProgressMode::kBar, [&] { return now_s; });
    progress.begin("tune", 2);
    now_s = 4.0;
    progress.step("EB: linear stage");
    // Unnamed units within 0.1 s of the last redraw do not redraw.
    progress.advance(0);
    now_s = 4.05;
    progress.begin("validate", 0);
  }
  const std::string text = out.str();
  EXPECT_NE(text.find("\r\x1b[K[" + std::string(12, '#') + std::string(12, '.') +
                      "] tune [1/2] EB: linear stage (4 s elapsed, about 4 s left)"),
            std::string::npos)
      << text;
  // The bar line is closed by a newline before the next task and when the Progress ends.
  EXPECT_EQ(lines(text).size(), 2U) << text;
  EXPECT_EQ(text.back(), '\n');
}

TEST(ProgressTest, QuietPrintsNothing) {
  std::ostringstream out;
  Progress progress(out, ProgressMode::kQuiet);
  progress.begin("tune", 3);
  progress.step("a");
  progress.advance(5);
  progress.end("x");
  EXPECT_TRUE(out.str().empty());
  Progress& shared = progressOrQuiet(nullptr);
  EXPECT_EQ(shared.mode(), ProgressMode::kQuiet);
  EXPECT_EQ(&progressOrQuiet(&progress), &progress);
}

TEST(ProgressTest, ModeForAFileIsLinesAndQuietWins) {
  EXPECT_EQ(progressModeFor(-1, false), ProgressMode::kLines);  // not a terminal
  EXPECT_EQ(progressModeFor(-1, true), ProgressMode::kQuiet);
}

TEST(ProgressTest, ConcurrentJobsCountEveryUnit) {
  std::ostringstream out;
  Progress progress(out, ProgressMode::kLines);
  progress.begin("jobs", 4000);
  JobPool pool(4);
  pool.run(40, [&](int) {
    for (int i = 0; i < 100; ++i) progress.advance();
  });
  EXPECT_EQ(progress.done(), 4000U);
  progress.end();
  // Every line is whole: the lock keeps lines from interleaving.
  for (const std::string& line : lines(out.str())) {
    EXPECT_EQ(line.rfind("jobs", 0), 0U) << line;
  }
}

}  // namespace
}  // namespace fullarm::core
