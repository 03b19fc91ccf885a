// fullarm::reports::Report: summary.json contents, write(), and the Report-level checks.

#include "fullarm/reports/report.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

#include "report_test_util.hpp"

namespace fullarm::reports {
namespace {

namespace fs = std::filesystem;
using test::freshTempDir;
using test::makeSampleReport;
using test::readFile;

// 2024-03-01T12:34:56Z
constexpr std::chrono::sys_seconds kFixedTime{std::chrono::seconds{1709296496}};

// Matches if calling `statement` throws `type` with a message containing every fragment.
template <typename Exception, typename Function>
void expectThrowsWith(Function&& statement, std::initializer_list<std::string> fragments) {
  try {
    statement();
    ADD_FAILURE() << "expected an exception";
  } catch (const Exception& error) {
    const std::string message = error.what();
    for (const std::string& fragment : fragments) {
      EXPECT_NE(message.find(fragment), std::string::npos)
          << "message \"" << message << "\" lacks \"" << fragment << "\"";
    }
  }
}

TEST(ReportSummary, WrittenFileParsesBackWithEveryKeyAndValue) {
  Report report = makeSampleReport();
  report.setCreatedTime(kFixedTime);
  report.addFile("trajectory.csv");
  const fs::path dir = freshTempDir() / "out";

  const std::vector<fs::path> written = report.write(dir);

  const nlohmann::json summary = nlohmann::json::parse(readFile(dir / "summary.json"));
  EXPECT_EQ(summary.size(), 9U);
  EXPECT_EQ(summary.at("schema_version"), 1);
  EXPECT_EQ(summary.at("fullarm_version"), FULLARM_TEST_PROJECT_VERSION);
  EXPECT_EQ(summary.at("subcommand"), "demo");
  EXPECT_EQ(summary.at("title"), "Sample report");
  EXPECT_EQ(summary.at("created_utc"), "2024-03-01T12:34:56Z");
  EXPECT_EQ(summary.at("verdict"), (nlohmann::json{{"pass", true}, {"headline", "All checks passed"}}));
  ASSERT_EQ(summary.at("headline_numbers").size(), 2U);
  EXPECT_EQ(summary.at("headline_numbers")[0],
            (nlohmann::json{{"key", "gain_margin_db"}, {"label", "Gain margin"}, {"value", 8.1}, {"unit", "dB"}}));
  EXPECT_EQ(summary.at("headline_numbers")[1].at("key"), "settling_time_s");
  EXPECT_DOUBLE_EQ(summary.at("headline_numbers")[1].at("value").get<double>(), 0.125);
  EXPECT_EQ(summary.at("results"), (nlohmann::json{{"gains", {{"k_p", 120.0}, {"k_d", 4.5}}}}));
  EXPECT_EQ(summary.at("files"), (nlohmann::json{"summary.json", "report.html", "trajectory.csv"}));

  EXPECT_EQ(written, (std::vector<fs::path>{dir / "summary.json", dir / "report.html", dir / "trajectory.csv"}));
  EXPECT_TRUE(fs::is_regular_file(dir / "report.html"));
  EXPECT_FALSE(fs::exists(dir / "summary.json.tmp"));
}

TEST(ReportSummary, KeysComeInTheDocumentedOrder) {
  const nlohmann::ordered_json summary = makeSampleReport().summary();
  std::vector<std::string> keys;
  for (const auto& item : summary.items()) {
    keys.push_back(item.key());
  }
  EXPECT_EQ(keys, (std::vector<std::string>{"schema_version", "fullarm_version", "subcommand", "title", "created_utc",
                                            "verdict", "headline_numbers", "results", "files"}));
}

TEST(ReportSummary, FailVerdictIsWrittenAsFalse) {
  Report report("tune", "Gains");
  report.setVerdict(false, "Unstable: gain margin -2 dB");
  EXPECT_FALSE(report.passed());
  const nlohmann::json summary = nlohmann::json::parse(report.summary().dump());
  EXPECT_EQ(summary.at("verdict").at("pass"), false);
  EXPECT_EQ(summary.at("verdict").at("headline"), "Unstable: gain margin -2 dB");
}

TEST(ReportSummary, NonFiniteNumbersBecomeNullAndTheJsonStaysValid) {
  Report report("identify", "Fit");
  report.setVerdict(false, "Fit failed");
  report.addHeadlineNumber("fit_percent", "Fit", std::numeric_limits<double>::quiet_NaN(), "%");
  report.results()["residual"] = std::numeric_limits<double>::infinity();
  const fs::path dir = freshTempDir();
  report.write(dir);
  const nlohmann::json summary = nlohmann::json::parse(readFile(dir / "summary.json"));
  EXPECT_TRUE(summary.at("headline_numbers")[0].at("value").is_null());
  EXPECT_TRUE(summary.at("results").at("residual").is_null());
}

TEST(ReportSummary, CreatedTimeDefaultsToConstructionTime) {
  const auto before = std::chrono::floor<std::chrono::seconds>(std::chrono::system_clock::now());
  const Report report("demo", "Now");
  const auto after = std::chrono::system_clock::now();
  EXPECT_GE(report.createdTime(), before);
  EXPECT_LE(report.createdTime(), after);
}

TEST(ReportWrite, WithoutVerdictThrowsAndWritesNothing) {
  const Report report("demo", "No verdict");
  const fs::path dir = freshTempDir() / "out";
  expectThrowsWith<std::logic_error>([&] { report.write(dir); }, {"setVerdict", "No verdict"});
  EXPECT_FALSE(fs::exists(dir));
}

TEST(ReportWrite, ResultsThatAreNotAnObjectThrow) {
  Report report("demo", "Bad results");
  report.setVerdict(true, "ok");
  report.results() = nlohmann::json::array({1, 2});
  expectThrowsWith<std::logic_error>([&] { report.summary(); }, {"results()", "object", "array"});
}

TEST(ReportWrite, UnwritableFolderThrowsNamingThePathAndTheOsError) {
  // A folder below a regular file cannot be created, even by root.
  const fs::path base = freshTempDir();
  { std::ofstream(base / "plain_file") << "x"; }
  const fs::path dir = base / "plain_file" / "out";
  const Report report = makeSampleReport();
  expectThrowsWith<std::runtime_error>([&] { report.write(dir); }, {dir.string(), "Not a directory"});
}

TEST(ReportWrite, UnwritableFileThrowsNamingThePathAndTheOsError) {
  // A folder where report.html should go cannot be replaced by the file.
  const fs::path dir = freshTempDir();
  fs::create_directories(dir / "report.html" / "occupied");
  const Report report = makeSampleReport();
  expectThrowsWith<std::runtime_error>([&] { report.write(dir); }, {(dir / "report.html").string(), "Is a directory"});
  EXPECT_FALSE(fs::exists(dir / "report.html.tmp"));
}

TEST(ReportWrite, OverwritesAnEarlierReport) {
  const fs::path dir = freshTempDir();
  Report first("demo", "First");
  first.setVerdict(false, "first");
  first.write(dir);
  Report second("demo", "Second");
  second.setVerdict(true, "second");
  second.write(dir);
  EXPECT_EQ(nlohmann::json::parse(readFile(dir / "summary.json")).at("title"), "Second");
}

TEST(ReportInput, EmptySubcommandIsRejected) {
  expectThrowsWith<std::invalid_argument>([] { Report report("", "Title"); }, {"subcommand"});
}

TEST(ReportInput, HeadlineKeyMustBeSnakeCase) {
  Report report("demo", "Keys");
  expectThrowsWith<std::invalid_argument>([&] { report.addHeadlineNumber("Gain Margin", "Gain margin", 1.0, "dB"); },
                                          {"\"Gain Margin\"", "snake_case"});
}

TEST(ReportInput, HeadlineKeyMustBeUnique) {
  Report report("demo", "Keys");
  report.addHeadlineNumber("gain_margin_db", "Gain margin", 1.0, "dB");
  expectThrowsWith<std::invalid_argument>([&] { report.addHeadlineNumber("gain_margin_db", "Again", 2.0, "dB"); },
                                          {"gain_margin_db", "twice"});
}

TEST(ReportInput, AttachedFileMustBeRelative) {
  Report report("demo", "Files");
  expectThrowsWith<std::invalid_argument>([&] { report.addFile("/tmp/log.csv"); }, {"/tmp/log.csv", "relative"});
}

TEST(ReportInput, AttachedFileMustStayInsideTheFolder) {
  Report report("demo", "Files");
  expectThrowsWith<std::invalid_argument>([&] { report.addFile("../log.csv"); }, {"../log.csv", ".."});
}

TEST(ReportInput, AttachedFileMustNotBeListedTwice) {
  Report report("demo", "Files");
  report.addFile("logs/session.lcm");
  expectThrowsWith<std::invalid_argument>([&] { report.addFile("logs/./session.lcm"); }, {"already listed"});
  expectThrowsWith<std::invalid_argument>([&] { report.addFile("summary.json"); }, {"already listed"});
}

TEST(ReportInput, SectionReferencesStayValidAsSectionsAreAdded) {
  Report report("demo", "Sections");
  Section& first = report.addSection("First");
  for (int i = 0; i < 100; ++i) {
    report.addSection("More");
  }
  first.addParagraph("still here");
  EXPECT_EQ(report.sections().front().blocks().size(), 1U);
}

TEST(Versions, AreTheBuildVersions) {
  EXPECT_EQ(fullarmVersion(), FULLARM_TEST_PROJECT_VERSION);
  EXPECT_EQ(plotlyVersion(), FULLARM_TEST_PLOTLY_VERSION);
}

}  // namespace
}  // namespace fullarm::reports
