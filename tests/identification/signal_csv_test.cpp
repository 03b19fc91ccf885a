// Signal and experiment-log CSV: exact round trip, and every malformed input rejected with an
// error naming its line (hand-made cases, then seeded mutations and truncations of a valid log).

#include "fullarm/identification/signal_csv.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "fullarm/core/random.hpp"
#include "scratch_dir.hpp"

namespace fullarm::identification {
namespace {

const std::string kValid =
    "time_s,excitation_v,command_v,q_rad,tau_measured_nm\n"
    "0,0.1,0.2,0.3,1.5\n"
    "0.001,-0.1,0.25,0.31,1.25\n"
    "0.002,0.05,-0.5,0.32,-2e-3\n";

std::size_t errorLine(const std::string& text) {
  try {
    (void)parseSignalCsv(text, "log.csv", kExperimentColumns);
  } catch (const CsvFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("log.csv"), std::string::npos) << e.what();
    return e.line();
  }
  ADD_FAILURE() << "accepted:\n" << text;
  return 0;
}

std::string errorText(const std::string& text) {
  try {
    (void)parseSignalCsv(text, "log.csv", kExperimentColumns);
  } catch (const CsvFormatError& e) {
    return e.what();
  }
  return {};
}

TEST(SignalCsvTest, ParsesAValidLogInAnyColumnOrder) {
  const SignalTable t = parseSignalCsv(kValid, "log.csv", kExperimentColumns);
  ASSERT_EQ(t.rows(), 3u);
  EXPECT_EQ(t.names.front(), "time_s");
  EXPECT_DOUBLE_EQ(t.column("tau_measured_nm")[2], -2e-3);
  EXPECT_DOUBLE_EQ(t.column("q_rad")[1], 0.31);
  const SignalTable swapped =
      parseSignalCsv("q_rad, time_s\r\n1, 0\r\n2, 0.5\r\n\n", "x.csv", {"q_rad"});  // CRLF, spaces, blank end
  EXPECT_EQ(swapped.names.front(), "time_s");
  EXPECT_EQ(swapped.column("time_s")[1], 0.5);
  EXPECT_EQ(swapped.column("q_rad")[1], 2.0);
  EXPECT_THROW((void)t.column("p_a_pa"), std::out_of_range);
  EXPECT_EQ(columnUnit("tau_measured_nm"), "nm");
  EXPECT_EQ(columnUnit("time"), "");
}

TEST(SignalCsvTest, RoundTripIsExact) {
  core::RandomStream rng(7, 1, 0);
  SignalTable t;
  t.names = kExperimentColumns;
  t.columns.assign(t.names.size(), {});
  for (int k = 0; k < 500; ++k) {
    t.columns[0].push_back(k * 1.0e-3);
    for (std::size_t c = 1; c < t.names.size(); ++c) t.columns[c].push_back(rng.uniform(-1e3, 1e3) * rng.uniform01());
  }
  const auto dir = test::scratchDir("identification_csv");
  writeSignalCsv(dir / "log.csv", t);
  const SignalTable back = readSignalCsv(dir / "log.csv", kExperimentColumns);
  ASSERT_EQ(back.names, t.names);
  for (std::size_t c = 0; c < t.names.size(); ++c) EXPECT_EQ(back.columns[c], t.columns[c]) << t.names[c];
}

TEST(SignalCsvTest, WriterRefusesRaggedTablesAndAMissingTimeColumn) {
  const auto dir = test::scratchDir("identification_csv_writer");
  SignalTable t;
  t.names = {"time_s", "q_rad"};
  t.columns = {{0.0, 1.0}, {0.0}};
  EXPECT_THROW(writeSignalCsv(dir / "a.csv", t), std::invalid_argument);
  t.names = {"q_rad", "time_s"};
  t.columns = {{0.0}, {0.0}};
  EXPECT_THROW(writeSignalCsv(dir / "b.csv", t), std::invalid_argument);
  t.names = {"time_s", "q_rad"};
  EXPECT_THROW(writeSignalCsv(dir / "no_such_dir" / "c.csv", t), std::runtime_error);
}

TEST(SignalCsvTest, MalformedLogsNameTheLine) {
  // Empty file, whitespace only, header without rows.
  EXPECT_EQ(errorLine(""), 1u);
  EXPECT_EQ(errorLine("\n\n"), 1u);
  EXPECT_NE(errorText("").find("empty file"), std::string::npos);
  EXPECT_EQ(errorLine("time_s,excitation_v,command_v,q_rad,tau_measured_nm\n"), 1u);
  // Missing column, and the same column in another unit.
  EXPECT_EQ(errorLine("time_s,excitation_v,command_v,q_rad\n0,0,0,0\n"), 1u);
  EXPECT_NE(errorText("time_s,excitation_v,command_v,q_rad\n0,0,0,0\n").find("missing column 'tau_measured_nm'"),
            std::string::npos);
  const std::string deg = "time_s,excitation_v,command_v,q_deg,tau_measured_nm\n0,0,0,0,0\n";
  EXPECT_EQ(errorLine(deg), 1u);
  EXPECT_NE(errorText(deg).find("'q_deg' is in unit 'deg'"), std::string::npos) << errorText(deg);
  EXPECT_EQ(errorLine("time_ms,excitation_v,command_v,q_rad,tau_measured_nm\n0,0,0,0,0\n"), 1u);
  EXPECT_EQ(errorLine("time_s,time_s,excitation_v,command_v,q_rad,tau_measured_nm\n0,0,0,0,0,0\n"), 1u);
  EXPECT_EQ(errorLine("time_s,,excitation_v,command_v,q_rad,tau_measured_nm\n0,0,0,0,0,0\n"), 1u);
  // Rows: time not increasing (equal, then backwards), NaN, infinity, garbage, short, long, empty field.
  const std::string header = "time_s,excitation_v,command_v,q_rad,tau_measured_nm\n";
  EXPECT_EQ(errorLine(header + "0,0,0,0,0\n0.001,0,0,0,0\n0.001,0,0,0,0\n"), 4u);
  EXPECT_EQ(errorLine(header + "0,0,0,0,0\n-1,0,0,0,0\n"), 3u);
  EXPECT_NE(errorText(header + "0,0,0,0,0\n-1,0,0,0,0\n").find("does not increase"), std::string::npos);
  EXPECT_EQ(errorLine(header + "0,0,0,0,0\n0.001,0,0,nan,0\n"), 3u);
  EXPECT_NE(errorText(header + "0,0,0,0,0\n0.001,0,0,nan,0\n").find("column 'q_rad': 'nan' is not finite"),
            std::string::npos);
  EXPECT_EQ(errorLine(header + "0,0,0,0,inf\n"), 2u);
  EXPECT_EQ(errorLine(header + "0,0,0,0,1.2.3\n"), 2u);
  EXPECT_EQ(errorLine(header + "0,0,0,0,abc\n"), 2u);
  EXPECT_EQ(errorLine(header + "0,0,0,0\n"), 2u);
  EXPECT_EQ(errorLine(header + "0,0,0,0,0,0\n"), 2u);
  EXPECT_EQ(errorLine(header + "0,0,,0,0\n"), 2u);
  EXPECT_EQ(errorLine(header + "0,0,0,0,0\n\n0.002,0,0,0,0\n"), 3u);  // a blank line inside the data
}

TEST(SignalCsvTest, UnreadableFileIsNamed) {
  try {
    (void)readSignalCsv("/nonexistent/dir/log.csv", kExperimentColumns);
    FAIL() << "no error";
  } catch (const CsvFormatError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/log.csv"), std::string::npos);
    EXPECT_EQ(e.line(), 0u);
  }
}

// Every accepted text must satisfy the reader's promises; every rejected one must be a
// CsvFormatError whose line exists in the text (a mutation never crashes the reader).
void checkMutant(const std::string& text) {
  const std::size_t lines = static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')) + 1;
  try {
    const SignalTable t = parseSignalCsv(text, "fuzz.csv", kExperimentColumns);
    ASSERT_GT(t.rows(), 0u);
    ASSERT_EQ(t.names.front(), "time_s");
    for (const auto& name : kExperimentColumns) ASSERT_TRUE(t.has(name)) << name;
    for (const auto& c : t.columns) {
      ASSERT_EQ(c.size(), t.rows());
      for (double v : c) ASSERT_TRUE(std::isfinite(v));
    }
    for (std::size_t r = 1; r < t.rows(); ++r) ASSERT_GT(t.columns[0][r], t.columns[0][r - 1]);
  } catch (const CsvFormatError& e) {
    ASSERT_GE(e.line(), 1u) << e.what();
    ASSERT_LE(e.line(), lines) << e.what();
  }
}

TEST(SignalCsvTest, FuzzedLogsAreAcceptedConsistentlyOrRejectedWithALine) {
  for (std::size_t cut = 0; cut <= kValid.size(); ++cut) checkMutant(kValid.substr(0, cut));
  const std::string alphabet = "0123456789.,-+eEnaif_ \n\rxq";
  for (std::uint64_t trial = 0; trial < 3000; ++trial) {
    core::RandomStream rng(11, 2, trial);
    std::string text = kValid;
    const int edits = rng.uniformInt(1, 4);
    for (int e = 0; e < edits; ++e) {
      const auto pos = static_cast<std::size_t>(rng.uniformInt(0, static_cast<int>(text.size()) - 1));
      const char c = alphabet[static_cast<std::size_t>(rng.uniformInt(0, static_cast<int>(alphabet.size()) - 1))];
      switch (rng.uniformInt(0, 2)) {
        case 0:
          text[pos] = c;
          break;
        case 1:
          text.insert(pos, 1, c);
          break;
        default:
          text.erase(pos, 1);
          break;
      }
      if (text.empty()) break;
    }
    checkMutant(text);
  }
}

}  // namespace
}  // namespace fullarm::identification
