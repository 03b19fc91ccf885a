#pragma once

/// @file
/// Chart descriptions for report.html: line and scatter charts, histograms and heat maps.
///
/// A chart is plain data. `Section::add*` validates it (throwing `std::invalid_argument` with
/// a message that names the chart title and what was expected) and the report renders it with
/// the inlined Plotly library.
///
/// Missing values: a NaN in a series, a heat map cell or a histogram sample marks a missing
/// value. It is written as JSON `null` and drawn as a gap (series), a blank cell (heat map), or
/// left out of the counts (histogram, with a note under the chart). Infinities are rejected.

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace fullarm::reports {

/// One chart axis.
struct Axis {
  /// Quantity name, e.g. "Frequency" or "Joint 2 torque".
  std::string label{};
  /// Unit symbol shown after the label as "label [unit]", e.g. "Hz", "N·m", "rad/s". Empty for
  /// a dimensionless quantity.
  std::string unit{};
  /// Logarithmic (base 10) axis. Every plotted, non-missing value on it must be > 0.
  bool log = false;
};

/// How the points of a series are drawn.
enum class SeriesMode {
  kAuto,          ///< Lines in a line chart, markers in a scatter chart.
  kLines,         ///< Connected line, no markers.
  kMarkers,       ///< Markers only.
  kLinesMarkers,  ///< Line with a marker on every point.
};

/// One named x/y data series of a line or scatter chart.
struct Series {
  /// Legend name.
  std::string name{};
  /// Abscissae, in the unit of the chart's x axis.
  std::vector<double> x{};
  /// Ordinates, in the unit of the chart's y axis; same size as `x`.
  std::vector<double> y{};
  /// Drawing mode.
  SeriesMode mode = SeriesMode::kAuto;
  /// Optional hover text per point (for example a trial name); empty, or the same size as `x`.
  std::vector<std::string> point_labels{};
};

/// A line or scatter chart: one or more series on shared x and y axes.
struct XyChart {
  /// Title shown above the chart (required, also used in error messages).
  std::string title{};
  Axis x_axis{};
  Axis y_axis{};
  /// At least one series.
  std::vector<Series> series{};
  /// Optional note shown under the chart.
  std::string caption{};
};

/// One named sample set of a histogram.
struct HistogramSeries {
  /// Legend name.
  std::string name{};
  /// Samples, in the unit of the histogram's x axis. NaN samples are skipped and counted.
  std::vector<double> samples{};
};

/// A histogram of one or more sample sets on shared bins (computed in C++, see
/// computeHistogramBins()). The y axis is the sample count per bin.
struct Histogram {
  /// Title shown above the chart (required, also used in error messages).
  std::string title{};
  /// The binned quantity. With `x_axis.log` the bins are equally wide in log10 space and every
  /// sample must be > 0.
  Axis x_axis{};
  /// At least one sample set.
  std::vector<HistogramSeries> series{};
  /// Number of bins; 0 chooses it from the data (Freedman–Diaconis rule, at most 100 bins).
  std::size_t bin_count = 0;
  /// Optional bin range {low, high} in x-axis units (low < high). Without it the range spans
  /// all samples. Samples outside it are left out and counted in a note under the chart.
  std::optional<std::array<double, 2>> range{};
  /// Optional note shown under the chart.
  std::string caption{};
};

/// Colour scale of a heat map.
enum class ColorScale {
  kSequential,  ///< Viridis: low to high.
  kDiverging,   ///< Blue (negative), white (zero), red (positive): signed quantities.
};

/// A heat map: z sampled on a grid of x (columns) by y (rows).
struct HeatMap {
  /// Title shown above the chart (required, also used in error messages).
  std::string title{};
  Axis x_axis{};
  Axis y_axis{};
  /// Label and unit of the colour bar (the `log` flag is ignored: the colour scale is linear).
  Axis z_axis{};
  /// Column centres, in x-axis units: finite, strictly increasing or strictly decreasing.
  std::vector<double> x{};
  /// Row centres, in y-axis units: finite, strictly increasing or strictly decreasing.
  std::vector<double> y{};
  /// Values, row-major: `z[row][column]`, `y.size()` rows of `x.size()` columns. NaN marks a
  /// cell without a value (drawn blank).
  std::vector<std::vector<double>> z{};
  ColorScale color_scale = ColorScale::kSequential;
  /// Optional note shown under the chart.
  std::string caption{};
};

/// Bins shared by all series of a histogram.
struct HistogramBins {
  /// Bin edges, size `bin_count + 1`, increasing. Bin i is [edges[i], edges[i+1]); the last
  /// bin also holds samples equal to its upper edge.
  std::vector<double> edges{};
  /// Per series, the sample count of each bin (size `edges.size() - 1`).
  std::vector<std::vector<std::size_t>> counts{};
  /// Per series, the number of NaN samples skipped.
  std::vector<std::size_t> missing{};
  /// Per series, the number of samples outside an explicit `Histogram::range`.
  std::vector<std::size_t> out_of_range{};
};

/// Validates a histogram and bins its samples.
///
/// With no samples at all the result has one bin [0, 1) (or [1, 10) on a log axis) and zero
/// counts.
/// @throws std::invalid_argument naming the histogram title if it has no title or no series,
///   if a sample is infinite, if a sample is <= 0 on a log axis, or if `range` is not a finite
///   low < high (both > 0 on a log axis).
HistogramBins computeHistogramBins(const Histogram& histogram);

}  // namespace fullarm::reports
