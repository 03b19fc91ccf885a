#pragma once

/// @file
/// A report section: a heading followed by paragraphs, tables and charts, in the order added.

#include <string>
#include <variant>
#include <vector>

#include "fullarm/reports/charts.hpp"
#include "fullarm/reports/replay3d.hpp"
#include "fullarm/reports/table.hpp"

namespace fullarm::reports {

/// A paragraph of plain text (HTML-escaped on output; line breaks are kept).
struct Paragraph {
  std::string text{};
};

/// A line chart: an XyChart whose `SeriesMode::kAuto` series are drawn as lines.
struct LineChart {
  XyChart chart{};
};

/// A scatter chart: an XyChart whose `SeriesMode::kAuto` series are drawn as markers.
struct ScatterChart {
  XyChart chart{};
};

/// A section of report.html. Obtain one from Report::addSection(); every `add*` function
/// validates its input, appends it and returns `*this` so calls can be chained.
class Section {
 public:
  /// One piece of content.
  using Block = std::variant<Paragraph, Table, LineChart, ScatterChart, Histogram, HeatMap, Replay3d>;

  /// A section with the given heading (may be empty: no heading is shown).
  explicit Section(std::string heading);

  /// Appends a paragraph of plain text.
  Section& addParagraph(std::string text);

  /// Appends a table.
  /// @throws std::invalid_argument naming the caption if there are no columns, if a row does
  ///   not have one cell per column, or if `significant_digits` is outside 1..17.
  Section& addTable(Table table);

  /// Appends a line chart (`SeriesMode::kAuto` series are drawn as lines).
  /// @throws std::invalid_argument naming the chart title if the title is empty, there is no
  ///   series, a series has x and y (or point_labels) of different sizes, a value is infinite,
  ///   or a value on a log axis is <= 0.
  Section& addLineChart(XyChart chart);

  /// Appends a scatter chart (`SeriesMode::kAuto` series are drawn as markers).
  /// @throws std::invalid_argument as addLineChart().
  Section& addScatterChart(XyChart chart);

  /// Appends a histogram; bins are computed with computeHistogramBins().
  /// @throws std::invalid_argument as computeHistogramBins().
  Section& addHistogram(Histogram histogram);

  /// Appends a heat map.
  /// @throws std::invalid_argument naming the chart title if the title is empty, x or y is
  ///   empty, not finite or not strictly monotonic, a value on a log axis is <= 0, z is not
  ///   `y.size()` rows by `x.size()` columns, or a z value is infinite.
  Section& addHeatMap(HeatMap heat_map);

  /// Appends a 3D replay (drawn with the inlined three.js; see replay3d.hpp).
  /// @throws std::invalid_argument naming the replay title if the title is empty, there is no
  ///   link or no frame, a link radius or a scale is not a finite positive number, frame times
  ///   are not finite and strictly increasing, a frame does not hold one segment and one
  ///   penetration flag per link and one torque per joint, a triangle index is out of range,
  ///   or a coordinate, torque or force is not finite (or a force is negative).
  Section& addReplay3d(Replay3d replay);

  /// Lays the section's blocks out in `columns` side-by-side columns (1, the default: one
  /// below the other), filled row by row: with 2, blocks 1 and 2 share the first row, 3 and 4
  /// the second, ... (for example a full-arm and a hand-only run side by side). Narrow
  /// windows and print fall back to one column.
  /// @throws std::invalid_argument naming the heading if `columns` is not 1 .. 4
  Section& setColumns(int columns);
  /// Number of columns (see setColumns()).
  int columns() const noexcept { return columns_; }

  /// The heading.
  const std::string& heading() const noexcept { return heading_; }
  /// The content, in the order added.
  const std::vector<Block>& blocks() const noexcept { return blocks_; }

 private:
  std::string heading_;
  std::vector<Block> blocks_;
  int columns_ = 1;
};

}  // namespace fullarm::reports
