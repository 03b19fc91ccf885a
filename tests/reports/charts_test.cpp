// Section input validation: every bad chart or table throws std::invalid_argument naming the
// chart and what was expected. One test per case.

#include <gtest/gtest.h>

#include <limits>
#include <stdexcept>

#include "fullarm/reports/section.hpp"

namespace fullarm::reports {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Runs `statement`, which must throw std::invalid_argument whose message contains every
// fragment.
template <typename Function>
void expectInvalid(Function&& statement, std::initializer_list<std::string> fragments) {
  try {
    statement();
    ADD_FAILURE() << "expected std::invalid_argument";
  } catch (const std::invalid_argument& error) {
    const std::string message = error.what();
    for (const std::string& fragment : fragments) {
      EXPECT_NE(message.find(fragment), std::string::npos)
          << "message \"" << message << "\" lacks \"" << fragment << "\"";
    }
  }
}

XyChart validXyChart() {
  XyChart chart;
  chart.title = "Bode magnitude";
  chart.x_axis = {"Frequency", "Hz", true};
  chart.y_axis = {"Magnitude", "dB", false};
  chart.series.push_back({"joint 2", {1.0, 10.0, 100.0}, {0.0, -3.0, -20.0}});
  return chart;
}

HeatMap validHeatMap() {
  HeatMap heat_map;
  heat_map.title = "Reachability";
  heat_map.x_axis = {"x", "m", false};
  heat_map.y_axis = {"y", "m", false};
  heat_map.z_axis = {"Margin", "N", false};
  heat_map.x = {0.0, 0.1, 0.2};
  heat_map.y = {1.0, 0.5};
  heat_map.z = {{1.0, 2.0, 3.0}, {4.0, kNan, 6.0}};
  return heat_map;
}

TEST(ChartValidation, ValidChartsAreAccepted) {
  Section section("ok");
  section.addLineChart(validXyChart());
  section.addScatterChart(validXyChart());
  section.addHeatMap(validHeatMap());
  // Designated initializers, leaving members out, compile warning-free (-Wextra).
  section.addLineChart(
      {.title = "Loop gain", .x_axis = {"Frequency", "Hz", true}, .series = {{"joint 2", {1.0, 2.0}, {3.0, 4.0}}}});
  EXPECT_EQ(section.blocks().size(), 4U);
}

TEST(ChartValidation, AutoModeResolvesToLinesOrMarkers) {
  Section section("modes");
  XyChart chart = validXyChart();
  chart.series.push_back({"explicit", {1.0}, {1.0}, SeriesMode::kLinesMarkers, {}});
  section.addLineChart(chart);
  section.addScatterChart(chart);
  const auto& line = std::get<LineChart>(section.blocks()[0]).chart;
  const auto& scatter = std::get<ScatterChart>(section.blocks()[1]).chart;
  EXPECT_EQ(line.series[0].mode, SeriesMode::kLines);
  EXPECT_EQ(scatter.series[0].mode, SeriesMode::kMarkers);
  EXPECT_EQ(line.series[1].mode, SeriesMode::kLinesMarkers);
}

TEST(ChartValidation, SeriesSizeMismatch) {
  XyChart chart = validXyChart();
  chart.series[0].y.pop_back();
  expectInvalid([&] { Section("s").addLineChart(chart); },
                {"line chart \"Bode magnitude\"", "series \"joint 2\"", "3 x values but 2 y values"});
}

TEST(ChartValidation, PointLabelCountMismatch) {
  XyChart chart = validXyChart();
  chart.series[0].point_labels = {"a", "b"};
  expectInvalid([&] { Section("s").addScatterChart(chart); },
                {"scatter chart \"Bode magnitude\"", "2 point labels for 3 points"});
}

TEST(ChartValidation, NonPositiveValueOnLogAxis) {
  XyChart chart = validXyChart();
  chart.series[0].x[1] = 0.0;
  expectInvalid([&] { Section("s").addLineChart(chart); },
                {"\"Bode magnitude\"", "x[1] = 0", "not > 0", "x axis is logarithmic"});
}

TEST(ChartValidation, NegativeValueOnLogYAxis) {
  XyChart chart = validXyChart();
  chart.y_axis.log = true;
  expectInvalid([&] { Section("s").addLineChart(chart); }, {"\"Bode magnitude\"", "y[0] = 0", "y axis is logarithmic"});
}

TEST(ChartValidation, NanOnLogAxisIsAMissingValueNotAnError) {
  XyChart chart = validXyChart();
  chart.series[0].x[1] = kNan;
  EXPECT_NO_THROW(Section("s").addLineChart(chart));
}

TEST(ChartValidation, InfiniteValue) {
  XyChart chart = validXyChart();
  chart.series[0].y[2] = -kInf;
  expectInvalid([&] { Section("s").addLineChart(chart); },
                {"\"Bode magnitude\"", "y[2] is -inf", "expected a finite value"});
}

TEST(ChartValidation, MissingTitle) {
  XyChart chart = validXyChart();
  chart.title.clear();
  expectInvalid([&] { Section("s").addLineChart(chart); }, {"line chart (untitled)", "title is required"});
}

TEST(ChartValidation, NoSeries) {
  XyChart chart = validXyChart();
  chart.series.clear();
  expectInvalid([&] { Section("s").addLineChart(chart); }, {"\"Bode magnitude\"", "at least one series"});
}

TEST(HeatMapValidation, TooFewRows) {
  HeatMap heat_map = validHeatMap();
  heat_map.z.pop_back();
  expectInvalid([&] { Section("s").addHeatMap(heat_map); },
                {"heat map \"Reachability\"", "z has 1 rows", "expected 2 rows (y.size()) x 3 columns (x.size())"});
}

TEST(HeatMapValidation, RowWithWrongColumnCount) {
  HeatMap heat_map = validHeatMap();
  heat_map.z[1].push_back(7.0);
  expectInvalid([&] { Section("s").addHeatMap(heat_map); },
                {"heat map \"Reachability\"", "z row 1 has 4 columns", "expected 2 rows (y.size()) x 3 columns"});
}

TEST(HeatMapValidation, EmptyCoordinates) {
  HeatMap heat_map = validHeatMap();
  heat_map.x.clear();
  expectInvalid([&] { Section("s").addHeatMap(heat_map); }, {"\"Reachability\"", "x is empty"});
}

TEST(HeatMapValidation, NonMonotonicCoordinates) {
  HeatMap heat_map = validHeatMap();
  heat_map.x = {0.0, 0.2, 0.1};
  expectInvalid([&] { Section("s").addHeatMap(heat_map); },
                {"\"Reachability\"", "x is not strictly monotonic at index 2"});
}

TEST(HeatMapValidation, NanCoordinate) {
  HeatMap heat_map = validHeatMap();
  heat_map.y[0] = kNan;
  expectInvalid([&] { Section("s").addHeatMap(heat_map); }, {"\"Reachability\"", "y[0] is NaN", "finite"});
}

TEST(HeatMapValidation, InfiniteCell) {
  HeatMap heat_map = validHeatMap();
  heat_map.z[0][2] = kInf;
  expectInvalid([&] { Section("s").addHeatMap(heat_map); }, {"\"Reachability\"", "z[0][2] is inf"});
}

TEST(HeatMapValidation, NonPositiveCoordinateOnLogAxis) {
  HeatMap heat_map = validHeatMap();
  heat_map.x_axis.log = true;
  expectInvalid([&] { Section("s").addHeatMap(heat_map); }, {"\"Reachability\"", "x[0] = 0", "x axis is logarithmic"});
}

TEST(TableValidation, RowWithWrongCellCount) {
  Table table;
  table.caption = "Gains";
  table.columns = {"Gain", "Value"};
  table.rows = {{"k_p", 1.0}, {"k_d"}};
  expectInvalid([&] { Section("s").addTable(table); }, {"table \"Gains\"", "row 1 has 1 cells", "expected 2"});
}

TEST(TableValidation, NoColumns) {
  Table table;
  table.caption = "Empty";
  expectInvalid([&] { Section("s").addTable(table); }, {"table \"Empty\"", "at least one column"});
}

TEST(TableValidation, SignificantDigitsOutOfRange) {
  Table table;
  table.caption = "Digits";
  table.columns = {"a"};
  table.significant_digits = 0;
  expectInvalid([&] { Section("s").addTable(table); }, {"table \"Digits\"", "significant_digits is 0"});
}

TEST(HistogramValidation, InfiniteSample) {
  Histogram histogram;
  histogram.title = "Loop period";
  histogram.series.push_back({"tick", {1.0, kInf}});
  expectInvalid([&] { Section("s").addHistogram(histogram); },
                {"histogram \"Loop period\"", "sample set \"tick\" sample[1] is inf"});
}

TEST(HistogramValidation, NonPositiveSampleOnLogAxis) {
  Histogram histogram;
  histogram.title = "Loop period";
  histogram.x_axis = {"Period", "s", true};
  histogram.series.push_back({"tick", {1e-3, -1e-3}});
  expectInvalid([&] { Section("s").addHistogram(histogram); },
                {"histogram \"Loop period\"", "sample[1] = -0.001", "x axis is logarithmic"});
}

TEST(HistogramValidation, EmptyRange) {
  Histogram histogram;
  histogram.title = "Loop period";
  histogram.series.push_back({"tick", {1.0}});
  histogram.range = std::array<double, 2>{2.0, 2.0};
  expectInvalid([&] { Section("s").addHistogram(histogram); },
                {"histogram \"Loop period\"", "range is [2, 2]", "low < high"});
}

TEST(HistogramValidation, NoSampleSets) {
  Histogram histogram;
  histogram.title = "Loop period";
  expectInvalid([&] { Section("s").addHistogram(histogram); }, {"\"Loop period\"", "at least one sample set"});
}

}  // namespace
}  // namespace fullarm::reports
