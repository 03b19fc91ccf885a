// report.html: escaping, the JSON data block, no network references, the inlined plotly.js,
// and the order of the page.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fullarm/reports/report.hpp"
#include "report_test_util.hpp"

namespace fullarm::reports {
namespace {

using test::countOccurrences;
using test::jsonDataBlock;
using test::loadingReferences;
using test::makeSampleReport;
using test::readFile;
using test::toLower;

constexpr const char* kHostile = "</script><script>alert(\"x\")</script><!-- & 'q'";

TEST(HtmlEscaping, TitleWithScriptTagComesOutEscaped) {
  Report report("demo", "<script>alert(1)</script> & \"friends\"");
  report.setVerdict(true, "ok");
  const std::string html = report.html();
  EXPECT_EQ(html.find("<script>alert(1)"), std::string::npos);
  EXPECT_NE(html.find("<h1>&lt;script&gt;alert(1)&lt;/script&gt; &amp; &quot;friends&quot;</h1>"), std::string::npos);
  EXPECT_NE(html.find("<title>&lt;script&gt;alert(1)&lt;/script&gt;"), std::string::npos);
}

TEST(HtmlEscaping, EveryCallerTextIsEscaped) {
  Report report(kHostile, kHostile);
  report.setVerdict(false, kHostile);
  report.addHeadlineNumber("n", kHostile, 1.0, kHostile);
  report.addFile("a<b>.csv");
  Section& section = report.addSection(kHostile);
  section.addParagraph(kHostile);
  Table table;
  table.caption = kHostile;
  table.columns = {kHostile};
  table.rows = {{kHostile}};
  section.addTable(table);
  XyChart chart;
  chart.title = kHostile;
  chart.caption = kHostile;
  chart.series.push_back({kHostile, {1.0}, {2.0}, SeriesMode::kAuto, {kHostile}});
  section.addScatterChart(chart);

  const std::string html = report.html();
  // The only script tags are the page's own three elements.
  const std::string lower = toLower(html);
  EXPECT_EQ(countOccurrences(lower, "<script"), 3U);
  EXPECT_EQ(countOccurrences(lower, "</script"), 3U);
  EXPECT_EQ(countOccurrences(html, "alert(\"x\")"), 0U);
  EXPECT_EQ(countOccurrences(html, "<!-- &"), 0U);
  EXPECT_NE(html.find("href=\"a%3Cb%3E.csv\""), std::string::npos);
}

TEST(HtmlDataBlock, CannotBeBrokenOutOfByAClosingScriptTagInALabel) {
  Report report("demo", "Data block");
  report.setVerdict(true, "ok");
  XyChart chart;
  chart.title = "Chart";
  chart.x_axis = {kHostile, kHostile, false};
  chart.series.push_back({kHostile, {1.0, 2.0}, {3.0, 4.0}, SeriesMode::kAuto, {}});
  report.addSection("S").addLineChart(chart);
  const std::string html = report.html();

  // The block ends where the browser would end it; it must still be the whole, valid JSON
  // and give back the label.
  const std::string block = jsonDataBlock(html);
  ASSERT_FALSE(block.empty());
  EXPECT_EQ(block.find('<'), std::string::npos);
  const nlohmann::json data = nlohmann::json::parse(block);
  const nlohmann::json& trace = data.at("charts").at("chart-1").at("data").at(0);
  EXPECT_EQ(trace.at("name"),
            "&lt;/script&gt;&lt;script&gt;alert(&quot;x&quot;)&lt;/script&gt;&lt;!-- &amp; &#39;q&#39;");
  EXPECT_EQ(test::chartValues(trace.at("y")), (std::vector<double>{3.0, 4.0}));
}

TEST(HtmlDataBlock, NanStaysAGapAndTheBlockStaysValidJson) {
  Report report("demo", "Gaps");
  report.setVerdict(true, "ok");
  XyChart chart;
  chart.title = "With a gap";
  const double nan = std::numeric_limits<double>::quiet_NaN();
  chart.series.push_back({"s", {0.0, 1.0, 2.0}, {1.0, nan, 3.0}, SeriesMode::kAuto, {}});
  report.addSection("S").addLineChart(chart);
  const nlohmann::json data = nlohmann::json::parse(jsonDataBlock(report.html()));
  const std::vector<double> y = test::chartValues(data.at("charts").at("chart-1").at("data").at(0).at("y"));
  ASSERT_EQ(y.size(), 3U);
  EXPECT_EQ(y[0], 1.0);
  EXPECT_TRUE(std::isnan(y[1]));
  EXPECT_EQ(y[2], 3.0);
}

// Chart arrays travel as float32 where that is finer than a pixel, float64 where the values
// sit close together relative to their size, and evenly spaced x values as x0 and dx.
TEST(HtmlDataBlock, ChartArraysKeepTheirValues) {
  Report report("demo", "Arrays");
  report.setVerdict(true, "ok");
  XyChart chart;
  chart.title = "Arrays";
  std::vector<double> time_s;
  std::vector<double> wide;
  std::vector<double> narrow;
  std::vector<double> uneven;
  for (int i = 0; i < 1001; ++i) {
    time_s.push_back(0.25 + i * 1e-3);
    wide.push_back(std::sin(0.01 * i) * 123.456);
    narrow.push_back(1000.0 + 1e-4 * i);
    uneven.push_back(i * i * 1e-6);
  }
  chart.series.push_back({"wide", time_s, wide, SeriesMode::kLines, {}});
  chart.series.push_back({"narrow", uneven, narrow, SeriesMode::kLines, {}});
  report.addSection("S").addLineChart(chart);
  const nlohmann::json data = nlohmann::json::parse(jsonDataBlock(report.html()));
  const nlohmann::json& traces = data.at("charts").at("chart-1").at("data");

  const nlohmann::json& even = traces.at(0);
  EXPECT_FALSE(even.contains("x"));
  EXPECT_DOUBLE_EQ(even.at("x0").get<double>(), 0.25);
  EXPECT_NEAR(even.at("dx").get<double>(), 1e-3, 1e-15);
  EXPECT_EQ(even.at("y").at("dtype"), "f4");
  const std::vector<double> wide_read = test::chartValues(even.at("y"));
  ASSERT_EQ(wide_read.size(), wide.size());
  for (std::size_t i = 0; i < wide.size(); ++i) {
    EXPECT_NEAR(wide_read[i], wide[i], 1e-7 * 123.456) << i;
  }

  const nlohmann::json& close = traces.at(1);
  EXPECT_EQ(close.at("y").at("dtype"), "f8");
  EXPECT_EQ(test::chartValues(close.at("y")), narrow);
  const std::vector<double> x_read = test::chartValues(close.at("x"));
  ASSERT_EQ(x_read.size(), uneven.size());
  for (std::size_t i = 0; i < uneven.size(); ++i) {
    EXPECT_NEAR(x_read[i], uneven[i], 1e-7) << i;
  }
}

TEST(HtmlDataBlock, HeatMapValuesAreRowMajorWithTheirShape) {
  Report report("demo", "Heat map");
  report.setVerdict(true, "ok");
  HeatMap map;
  map.title = "Map";
  map.x = {0.0, 1.0, 2.0};
  map.y = {10.0, 20.0};
  map.z = {{1.0, 2.0, 3.0}, {4.0, std::numeric_limits<double>::quiet_NaN(), 6.0}};
  report.addSection("S").addHeatMap(map);
  const nlohmann::json data = nlohmann::json::parse(jsonDataBlock(report.html()));
  const nlohmann::json& trace = data.at("charts").at("chart-1").at("data").at(0);
  EXPECT_EQ(trace.at("z").at("shape"), "2,3");
  const std::vector<double> z = test::chartValues(trace.at("z"));
  ASSERT_EQ(z.size(), 6U);
  EXPECT_EQ(z[0], 1.0);
  EXPECT_EQ(z[2], 3.0);
  EXPECT_EQ(z[3], 4.0);
  EXPECT_TRUE(std::isnan(z[4]));
  EXPECT_EQ(z[5], 6.0);
  EXPECT_EQ(test::chartValues(trace.at("y")), (std::vector<double>{10.0, 20.0}));
}

TEST(HtmlNetwork, NoAttributeOrStyleLoadsFromTheNetwork) {
  Report report = makeSampleReport();
  report.addFile("logs/session log.csv");
  const std::string html = report.html();
  const std::vector<std::string> references = loadingReferences(html);
  // The scan sees the page's own links (section anchors, listed files) ...
  EXPECT_NE(std::find(references.begin(), references.end(), "report.html"), references.end());
  EXPECT_NE(std::find(references.begin(), references.end(), "logs/session%20log.csv"), references.end());
  // ... and none of them reaches the network.
  for (const std::string& reference : references) {
    EXPECT_FALSE(test::isNetworkReference(reference)) << reference;
  }
  // Outside the scripts there is no URL at all (plotly.js has URL strings in its code).
  EXPECT_EQ(test::withoutScriptContent(html).find("://"), std::string::npos);
}

TEST(HtmlNetwork, TheScanFindsNetworkReferences) {
  // The scanner above must be able to fail.
  const std::string html =
      "<html><head><link rel=stylesheet href='https://cdn.example/x.css'>"
      "<style>body{background:url(\"http://example.com/a.png\")} @import 'https://f.example/f.css';</style>"
      "<script src=\"//cdn.example/plotly.js\"></script><script>var u='https://a.b';</script></head>"
      "<body><img src=\"data:image/png;base64,AA\"><a href=\"#top\">x</a></body></html>";
  std::vector<std::string> network;
  for (const std::string& reference : loadingReferences(html)) {
    if (test::isNetworkReference(reference)) {
      network.push_back(reference);
    }
  }
  EXPECT_EQ(network, (std::vector<std::string>{"https://cdn.example/x.css", "//cdn.example/plotly.js",
                                               "http://example.com/a.png", "https://f.example/f.css"}));
}

TEST(HtmlNetwork, ContentSecurityPolicyForbidsLoading) {
  const std::string html = makeSampleReport().html();
  EXPECT_NE(html.find("<meta http-equiv=\"Content-Security-Policy\" content=\"default-src 'none';"), std::string::npos);
}

TEST(HtmlPlotly, LibraryIsInlinedWhole) {
  const std::string html = makeSampleReport().html();
  EXPECT_GT(html.size(), 1'000'000U);
  EXPECT_NE(html.find(std::string("plotly.js v") + std::string(plotlyVersion())), std::string::npos);
  // Byte for byte the bundle the build made, inside a script element.
  const std::string library = readFile(FULLARM_TEST_PLOTLY_JS);
  ASSERT_GT(library.size(), 1'000'000U);
  const std::size_t at = html.find(library);
  ASSERT_NE(at, std::string::npos);
  EXPECT_EQ(html.compare(at - 9, 9, "<script>\n"), 0);
}

TEST(HtmlLayout, HeadlineComesBeforeTheSections) {
  const std::string html = makeSampleReport().html();
  const std::size_t title = html.find("<h1>Sample report</h1>");
  const std::size_t verdict = html.find("<div class=\"verdict pass\"");
  const std::size_t badge = html.find("PASS", verdict);
  const std::size_t numbers = html.find("data-key=\"gain_margin_db\"");
  const std::size_t section = html.find("<h2>Results</h2>");
  const std::size_t chart = html.find("data-chart=\"chart-1\"");
  const std::size_t table = html.find("<caption>Gains</caption>");
  ASSERT_NE(title, std::string::npos);
  ASSERT_NE(chart, std::string::npos);
  ASSERT_NE(table, std::string::npos);
  EXPECT_LT(title, verdict);
  EXPECT_LT(verdict, badge);
  EXPECT_LT(badge, numbers);
  EXPECT_LT(numbers, section);
  EXPECT_LT(section, chart);
  EXPECT_LT(chart, table);
}

TEST(HtmlLayout, FailVerdictIsMarkedFail) {
  Report report("tune", "Gains");
  report.setVerdict(false, "Unstable");
  const std::string html = report.html();
  EXPECT_NE(html.find("<div class=\"verdict fail\" role=\"status\"><span class=\"badge\">FAIL</span>"),
            std::string::npos);
  EXPECT_EQ(html.find("verdict pass"), std::string::npos);
}

TEST(HtmlLayout, EveryChartHasADivAndAFigure) {
  Report report = makeSampleReport();
  Histogram histogram;
  histogram.title = "Timing";
  histogram.series.push_back({"loop", {1.0, 2.0, 2.5, 3.0}});
  report.addSection("More").addHistogram(histogram);
  const std::string html = report.html();
  const nlohmann::json data = nlohmann::json::parse(jsonDataBlock(html));
  EXPECT_EQ(data.at("charts").size(), 2U);
  for (const auto& [id, figure] : data.at("charts").items()) {
    EXPECT_NE(html.find("data-chart=\"" + id + "\""), std::string::npos) << id;
    EXPECT_TRUE(figure.at("data").is_array());
    EXPECT_TRUE(figure.at("layout").is_object());
  }
}

TEST(HtmlTable, NumbersAreFormattedAndRightAligned) {
  Report report("demo", "Table");
  report.setVerdict(true, "ok");
  Table table;
  table.caption = "Numbers";
  table.columns = {"Name", "Float", "Integer"};
  table.significant_digits = 3;
  table.rows = {{"a", 3.14159, 42}, {"b", std::numeric_limits<double>::quiet_NaN(), -7L}};
  report.addSection("S").addTable(table);
  const std::string html = report.html();
  EXPECT_NE(html.find("<tr><td>a</td><td class=\"num\">3.14</td><td class=\"num\">42</td></tr>"), std::string::npos);
  EXPECT_NE(html.find("<tr><td>b</td><td class=\"num\">NaN</td><td class=\"num\">-7</td></tr>"), std::string::npos);
}

}  // namespace
}  // namespace fullarm::reports
