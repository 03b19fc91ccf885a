#include "fullarm/reports/charts.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "text.hpp"

namespace fullarm::reports {
namespace {

// Upper bound of the automatic bin count, and of an explicit one.
constexpr std::size_t kMaxAutoBins = 100;
constexpr std::size_t kMaxBins = 100000;

using detail::checkValue;
using detail::failInput;
using detail::requireTitle;
using detail::Text;

// Quantile p of sorted values, linear interpolation between order statistics.
double quantile(const std::vector<double>& sorted, double p) {
  const double position = p * static_cast<double>(sorted.size() - 1);
  const auto below = static_cast<std::size_t>(std::floor(position));
  const std::size_t above = std::min(below + 1, sorted.size() - 1);
  const double fraction = position - static_cast<double>(below);
  return sorted[below] + fraction * (sorted[above] - sorted[below]);
}

}  // namespace

HistogramBins computeHistogramBins(const Histogram& histogram) {
  const std::string what = detail::describe("histogram", histogram.title);
  requireTitle(what, histogram.title);
  if (histogram.series.empty()) {
    failInput(what, Text() << "at least one sample set is required");
  }
  if (histogram.bin_count > kMaxBins) {
    failInput(what, Text() << "bin_count is " << histogram.bin_count << " (expected 0 for automatic, or 1 to "
                           << kMaxBins << ')');
  }
  const bool log = histogram.x_axis.log;
  // Binning happens in log10 space on a logarithmic axis.
  const auto to_bin_space = [log](double value) { return log ? std::log10(value) : value; };
  const auto from_bin_space = [log](double value) { return log ? std::pow(10.0, value) : value; };

  std::optional<std::array<double, 2>> range;
  if (histogram.range) {
    const auto [low, high] = *histogram.range;
    if (!std::isfinite(low) || !std::isfinite(high) || !(low < high)) {
      failInput(what, Text() << "range is [" << low << ", " << high << "] (expected finite low < high)");
    }
    if (log && low <= 0.0) {
      failInput(what, Text() << "range low = " << low << " is not > 0, but the x axis is logarithmic");
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
                 histogram.x_axis.log, 'x');
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
