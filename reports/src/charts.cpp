#include "fullarm/reports/charts.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "text.hpp"
#include "validation.hpp"

namespace fullarm::reports {
namespace {

// Upper bound of the automatic bin count, and of an explicit one.
constexpr std::size_t kMaxAutoBins = 100;
constexpr std::size_t kMaxBins = 100000;

using detail::Text;

[[noreturn]] void fail(const std::string& what, const Text& problem) {
  throw std::invalid_argument((Text() << what << ": " << problem.str()).str());
}

void requireTitle(const std::string& what, const std::string& title) {
  if (title.empty()) {
    fail(what, Text() << "a title is required");
  }
}

// Checks one value of a series axis: NaN (missing) is fine, infinity is not, and on a log axis
// the value must be > 0.
void checkValue(const std::string& what, const std::string& where, double value, const Axis& axis, char axis_name) {
  if (std::isnan(value)) {
    return;
  }
  if (std::isinf(value)) {
    fail(what, Text() << where << " is " << value << " (expected a finite value, or NaN for a missing value)");
  }
  if (axis.log && value <= 0.0) {
    fail(what, Text() << where << " = " << value << " is not > 0, but the " << axis_name << " axis is logarithmic");
  }
}

// Quantile p of sorted values, linear interpolation between order statistics.
double quantile(const std::vector<double>& sorted, double p) {
  const double position = p * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return sorted[below] + fraction * (sorted[above] - sorted[below]);
}

}  // namespace

namespace detail {

std::string describe(std::string_view kind, std::string_view title) {
  std::string out(kind);
  if (title.empty()) {
    out += " (untitled)";
  } else {
    out += " \"";
    out += title;
    out += '"';
  }
  return out;
}

void validateXyChart(const XyChart& chart, std::string_view kind) {
  const std::string what = describe(kind, chart.title);
  requireTitle(what, chart.title);
  if (chart.series.empty()) {
    fail(what, Text() << "at least one series is required");
  }
  for (const Series& series : chart.series) {
    const std::string name = (Text() << "series \"" << series.name << '"').str();
    if (series.x.size() != series.y.size()) {
      fail(what, Text() << name << " has " << series.x.size() << " x values but " << series.y.size()
                        << " y values (expected the same number)");
    }
    if (!series.point_labels.empty() && series.point_labels.size() != series.x.size()) {
      fail(what, Text() << name << " has " << series.point_labels.size() << " point labels for " << series.x.size()
                        << " points (expected none or one per point)");
    }
    for (std::size_t i = 0; i < series.x.size(); ++i) {
      checkValue(what, (Text() << name << " x[" << i << ']').str(), series.x[i], chart.x_axis, 'x');
      checkValue(what, (Text() << name << " y[" << i << ']').str(), series.y[i], chart.y_axis, 'y');
    }
  }
}

void validateHeatMap(const HeatMap& heat_map) {
  const std::string what = describe("heat map", heat_map.title);
  requireTitle(what, heat_map.title);
  const auto check_coordinates = [&](const std::vector<double>& values, const Axis& axis, char axis_name) {
    if (values.empty()) {
      fail(what, Text() << axis_name << " is empty (expected at least one " << (axis_name == 'x' ? "column" : "row")
                        << " centre)");
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
      const std::string where = (Text() << axis_name << '[' << i << ']').str();
      if (!std::isfinite(values[i])) {
        fail(what, Text() << where << " is " << values[i] << " (expected a finite value)");
      }
      checkValue(what, where, values[i], axis, axis_name);
    }
    if (values.size() >= 2) {
      const bool increasing = values[1] > values[0];
      for (std::size_t i = 1; i < values.size(); ++i) {
        if (increasing ? !(values[i] > values[i - 1]) : !(values[i] < values[i - 1])) {
          fail(what, Text() << axis_name << " is not strictly monotonic at index " << i << " (" << values[i - 1]
                            << " then " << values[i] << ')');
        }
      }
    }
  };
  check_coordinates(heat_map.x, heat_map.x_axis, 'x');
  check_coordinates(heat_map.y, heat_map.y_axis, 'y');

  const std::string expected = (Text() << "expected " << heat_map.y.size() << " rows (y.size()) x " << heat_map.x.size()
                                       << " columns (x.size())")
                                   .str();
  if (heat_map.z.size() != heat_map.y.size()) {
    fail(what, Text() << "z has " << heat_map.z.size() << " rows; " << expected);
  }
  for (std::size_t row = 0; row < heat_map.z.size(); ++row) {
    const std::vector<double>& values = heat_map.z[row];
    if (values.size() != heat_map.x.size()) {
      fail(what, Text() << "z row " << row << " has " << values.size() << " columns; " << expected);
    }
    for (std::size_t column = 0; column < values.size(); ++column) {
      if (std::isinf(values[column])) {
        fail(what, Text() << "z[" << row << "][" << column << "] is " << values[column]
                          << " (expected a finite value, or NaN for a cell without a value)");
      }
    }
  }
}

void validateTable(const Table& table) {
  const std::string what = describe("table", table.caption);
  if (table.columns.empty()) {
    fail(what, Text() << "at least one column is required");
  }
  if (table.significant_digits < 1 || table.significant_digits > 17) {
    fail(what, Text() << "significant_digits is " << table.significant_digits << " (expected 1 to 17)");
  }
  for (std::size_t row = 0; row < table.rows.size(); ++row) {
    if (table.rows[row].size() != table.columns.size()) {
      fail(what, Text() << "row " << row << " has " << table.rows[row].size() << " cells (expected "
                        << table.columns.size() << ", one per column)");
    }
  }
}

}  // namespace detail

HistogramBins computeHistogramBins(const Histogram& histogram) {
  const std::string what = detail::describe("histogram", histogram.title);
  requireTitle(what, histogram.title);
  if (histogram.series.empty()) {
    fail(what, Text() << "at least one sample set is required");
  }
  if (histogram.bin_count > kMaxBins) {
    fail(what,
         Text() << "bin_count is " << histogram.bin_count << " (expected 0 for automatic, or 1 to " << kMaxBins << ')');
  }
  const bool log = histogram.x_axis.log;
  // Binning happens in log10 space on a logarithmic axis.
  const auto to_bin_space = [log](double value) { return log ? std::log10(value) : value; };
  const auto from_bin_space = [log](double value) { return log ? std::pow(10.0, value) : value; };

  std::optional<std::array<double, 2>> range;
  if (histogram.range) {
    const auto [low, high] = *histogram.range;
    if (!std::isfinite(low) || !std::isfinite(high) || !(low < high)) {
      fail(what, Text() << "range is [" << low << ", " << high << "] (expected finite low < high)");
    }
    if (log && low <= 0.0) {
      fail(what, Text() << "range low = " << low << " is not > 0, but the x axis is logarithmic");
    }
    range = std::array<double, 2>{to_bin_space(low), to_bin_space(high)};
  }

  HistogramBins bins;
  const std::size_t series_count = histogram.series.size();
  bins.missing.assign(series_count, 0);
  bins.out_of_range.assign(series_count, 0);

  // Valid samples in bin space, per series.
  std::vector<std::vector<double>> values(series_count);
  std::vector<double> pooled;
  for (std::size_t s = 0; s < series_count; ++s) {
    const HistogramSeries& series = histogram.series[s];
    values[s].reserve(series.samples.size());
    for (std::size_t i = 0; i < series.samples.size(); ++i) {
      const double sample = series.samples[i];
      if (std::isnan(sample)) {
        ++bins.missing[s];
        continue;
      }
      checkValue(what, (Text() << "sample set \"" << series.name << "\" sample[" << i << ']').str(), sample,
                 histogram.x_axis, 'x');
      const double value = to_bin_space(sample);
      if (range && (value < (*range)[0] || value > (*range)[1])) {
        ++bins.out_of_range[s];
        continue;
      }
      values[s].push_back(value);
      pooled.push_back(value);
    }
  }
  std::sort(pooled.begin(), pooled.end());

  double low = 0.0;
  double high = 1.0;
  if (range) {
    low = (*range)[0];
    high = (*range)[1];
  } else if (!pooled.empty()) {
    low = pooled.front();
    high = pooled.back();
    if (low == high) {
      // All samples equal: one bin centred on the value.
      const double half_width = low != 0.0 ? 0.1 * std::fabs(low) : 0.5;
      low -= half_width;
      high += half_width;
    }
  }

  std::size_t bin_count = histogram.bin_count;
  if (bin_count == 0) {
    bin_count = 1;
    if (pooled.size() >= 2 && pooled.front() != pooled.back()) {
      // Freedman–Diaconis: bin width 2 IQR n^(-1/3); Sturges when the IQR is zero.
      const double n = static_cast<double>(pooled.size());
      const double iqr = quantile(pooled, 0.75) - quantile(pooled, 0.25);
      const double width = 2.0 * iqr / std::cbrt(n);
      const double count = width > 0.0 ? std::ceil((high - low) / width) : std::ceil(std::log2(n)) + 1.0;
      bin_count = static_cast<std::size_t>(std::clamp(count, 1.0, static_cast<double>(kMaxAutoBins)));
    }
  }

  const double width = (high - low) / static_cast<double>(bin_count);
  std::vector<double> edges(bin_count + 1);
  for (std::size_t i = 0; i <= bin_count; ++i) {
    edges[i] = i == bin_count ? high : low + width * static_cast<double>(i);
  }
  bins.counts.assign(series_count, std::vector<std::size_t>(bin_count, 0));
  for (std::size_t s = 0; s < series_count; ++s) {
    for (const double value : values[s]) {
      // Estimate the bin, then settle rounding at its edges against the edges themselves.
      const double position = std::floor((value - low) / width);
      auto index = static_cast<std::size_t>(std::clamp(position, 0.0, static_cast<double>(bin_count - 1)));
      while (index > 0 && value < edges[index]) {
        --index;
      }
      while (index + 1 < bin_count && value >= edges[index + 1]) {
        ++index;
      }
      ++bins.counts[s][index];
    }
  }
  bins.edges.reserve(edges.size());
  for (const double edge : edges) {
    bins.edges.push_back(from_bin_space(edge));
  }
  return bins;
}

}  // namespace fullarm::reports
