#include "fullarm/reports/section.hpp"

#include <utility>

#include "text.hpp"
#include "validation.hpp"

namespace fullarm::reports {
namespace {

// Resolves SeriesMode::kAuto so the stored chart says exactly how it is drawn.
XyChart withModes(XyChart chart, SeriesMode auto_mode) {
  for (Series& series : chart.series) {
    if (series.mode == SeriesMode::kAuto) {
      series.mode = auto_mode;
    }
  }
  return chart;
}

}  // namespace

Section::Section(std::string heading) : heading_(std::move(heading)) {}

Section& Section::addParagraph(std::string text) {
  blocks_.emplace_back(Paragraph{std::move(text)});
  return *this;
}

Section& Section::addTable(Table table) {
  detail::validateTable(table);
  blocks_.emplace_back(std::move(table));
  return *this;
}

Section& Section::addLineChart(XyChart chart) {
  detail::validateXyChart(chart, "line chart");
  blocks_.emplace_back(LineChart{withModes(std::move(chart), SeriesMode::kLines)});
  return *this;
}

Section& Section::addScatterChart(XyChart chart) {
  detail::validateXyChart(chart, "scatter chart");
  blocks_.emplace_back(ScatterChart{withModes(std::move(chart), SeriesMode::kMarkers)});
  return *this;
}

Section& Section::addHistogram(Histogram histogram) {
  computeHistogramBins(histogram);  // validates
  blocks_.emplace_back(std::move(histogram));
  return *this;
}

Section& Section::addHeatMap(HeatMap heat_map) {
  detail::validateHeatMap(heat_map);
  blocks_.emplace_back(std::move(heat_map));
  return *this;
}

Section& Section::setColumns(int columns) {
  if (columns < 1 || columns > 4) {
    detail::failInput(detail::describe("section", heading_), detail::Text()
                                                                 << "columns is " << columns << " (expected 1 .. 4)");
  }
  columns_ = columns;
  return *this;
}

Section& Section::addReplay3d(Replay3d replay) {
  detail::validateReplay3d(replay);
  blocks_.emplace_back(std::move(replay));
  return *this;
}

}  // namespace fullarm::reports
