#include "figures.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iterator>
#include <string>
#include <string_view>

#include "text.hpp"

namespace fullarm::reports::detail {
namespace {

using nlohmann::json;

constexpr const char* kFontFamily =
    "system-ui, -apple-system, 'Segoe UI', Roboto, 'Helvetica Neue', 'Noto Sans', "
    "'Liberation Sans', Arial, sans-serif";
// Okabe–Ito colours: distinguishable with the common colour-vision deficiencies.
constexpr const char* kColorway[] = {"#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"};
constexpr int kChartHeightPx = 420;
constexpr int kHeatMapHeightPx = 480;

std::string plotlyText(std::string_view text) {
  return escapeHtml(text);
}

json axisLayout(const Axis& axis) {
  return {
      {"title", {{"text", plotlyText(labelWithUnit(axis.label, axis.unit))}}},
      {"type", axis.log ? "log" : "linear"},
      {"automargin", true},
      {"showline", true},
      {"linecolor", "#9aa5b1"},
      {"gridcolor", "#e4e7eb"},
      {"zeroline", false},
      {"ticks", "outside"},
      {"tickcolor", "#9aa5b1"},
      {"exponentformat", "power"},
  };
}

json baseLayout(int height_px, bool show_legend) {
  json colorway = json::array();
  for (const char* color : kColorway) {
    colorway.push_back(color);
  }
  return {
      {"height", height_px},
      {"autosize", true},
      {"margin", {{"l", 64}, {"r", 24}, {"t", show_legend ? 40 : 12}, {"b", 56}}},
      {"font", {{"family", kFontFamily}, {"size", 13}, {"color", "#1f2933"}}},
      {"paper_bgcolor", "#ffffff"},
      {"plot_bgcolor", "#ffffff"},
      {"colorway", colorway},
      {"hovermode", "closest"},
      {"showlegend", show_legend},
      {"legend", {{"orientation", "h"}, {"x", 0}, {"xanchor", "left"}, {"y", 1.02}, {"yanchor", "bottom"}}},
  };
}

// "#rrggbb" -> "rgba(r, g, b, alpha)".
std::string withAlpha(std::string_view hex_color, double alpha) {
  const auto channel = [&](std::size_t at) { return std::stoi(std::string(hex_color.substr(at, 2)), nullptr, 16); };
  char text[48];
  std::snprintf(text, sizeof text, "rgba(%d, %d, %d, %.2f)", channel(1), channel(3), channel(5), alpha);
  return text;
}

const char* modeName(SeriesMode mode, bool scatter) {
  switch (mode) {
    case SeriesMode::kLines:
      return "lines";
    case SeriesMode::kMarkers:
      return "markers";
    case SeriesMode::kLinesMarkers:
      return "lines+markers";
    case SeriesMode::kAuto:
      break;
  }
  return scatter ? "markers" : "lines";
}

// Base64 (RFC 4648, with padding) of `bytes`.
std::string base64(const std::vector<unsigned char>& bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t n = (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8) | bytes[i + 2];
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += kAlphabet[(n >> 6) & 63];
    out += kAlphabet[n & 63];
  }
  if (i + 1 == bytes.size()) {
    const std::uint32_t n = std::uint32_t{bytes[i]} << 16;
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += "==";
  } else if (i + 2 == bytes.size()) {
    const std::uint32_t n = (std::uint32_t{bytes[i]} << 16) | (std::uint32_t{bytes[i + 1]} << 8);
    out += kAlphabet[(n >> 18) & 63];
    out += kAlphabet[(n >> 12) & 63];
    out += kAlphabet[(n >> 6) & 63];
    out += '=';
  }
  return out;
}

template <typename T>
void appendLittleEndian(std::vector<unsigned char>& bytes, T value) {
  unsigned char raw[sizeof(T)];
  std::memcpy(raw, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big) {
    std::reverse(std::begin(raw), std::end(raw));
  }
  bytes.insert(bytes.end(), std::begin(raw), std::end(raw));
}

// Below this ratio of an array's span to its largest magnitude, float32 rounding (relative
// 6e-8) would reach 1e-4 of the span, a fraction of a pixel no more: such arrays keep float64.
constexpr double kFloat32MinSpanRatio = 6e-4;

// A numeric array in Plotly's typed-array form {"dtype", "bdata": base64 of little-endian values},
// about a quarter the size of decimal text. float32 (7 significant digits, ample for a chart)
// unless the values sit so close together relative to their size that float32 would blur them.
// NaN (a missing value) stays NaN, which Plotly draws as a gap.
json typedArray(const std::vector<double>& values, const char* shape = nullptr) {
  double low = INFINITY;
  double high = -INFINITY;
  double magnitude = 0.0;
  bool fits_float = true;
  for (const double v : values) {
    if (std::isnan(v)) continue;
    low = std::min(low, v);
    high = std::max(high, v);
    magnitude = std::max(magnitude, std::abs(v));
    if (std::abs(v) > 3e38 || (v != 0.0 && std::abs(v) < 1e-37)) fits_float = false;
  }
  const bool use_float32 = fits_float && (magnitude == 0.0 || (high - low) >= kFloat32MinSpanRatio * magnitude);
  std::vector<unsigned char> bytes;
  bytes.reserve(values.size() * (use_float32 ? 4 : 8));
  for (const double v : values) {
    if (use_float32) {
      appendLittleEndian(bytes, static_cast<float>(v));
    } else {
      appendLittleEndian(bytes, v);
    }
  }
  json array = {{"dtype", use_float32 ? "f4" : "f8"}, {"bdata", base64(bytes)}};
  if (shape != nullptr) array["shape"] = shape;
  return array;
}

// Sets the trace's x values: `x0` and `dx` when they are evenly spaced (time axes), else `x`.
void setX(json& trace, const std::vector<double>& x) {
  if (x.size() >= 3 && std::isfinite(x.front()) && std::isfinite(x.back())) {
    const double dx = (x.back() - x.front()) / static_cast<double>(x.size() - 1);
    const double tolerance = 1e-9 * std::max(std::abs(x.front()), std::abs(x.back()));
    bool even = dx != 0.0;
    for (std::size_t i = 0; even && i < x.size(); ++i) {
      even = std::abs(x[i] - (x.front() + static_cast<double>(i) * dx)) <= tolerance;
    }
    if (even) {
      trace["x0"] = x.front();
      trace["dx"] = dx;
      return;
    }
  }
  trace["x"] = typedArray(x);
}

}  // namespace

json xyFigure(const XyChart& chart, bool scatter) {
  json data = json::array();
  for (const Series& series : chart.series) {
    json trace = {
        {"type", "scatter"},
        {"mode", modeName(series.mode, scatter)},
        {"name", plotlyText(series.name)},
        {"y", typedArray(series.y)},
        {"line", {{"width", 1.8}}},
        {"marker", {{"size", 6}}},
    };
    setX(trace, series.x);
    if (!series.point_labels.empty()) {
      json labels = json::array();
      for (const std::string& label : series.point_labels) {
        labels.push_back(plotlyText(label));
      }
      trace["text"] = std::move(labels);
      trace["hoverinfo"] = "x+y+text+name";
    }
    data.push_back(std::move(trace));
  }
  json layout = baseLayout(kChartHeightPx, chart.series.size() > 1);
  layout["xaxis"] = axisLayout(chart.x_axis);
  layout["yaxis"] = axisLayout(chart.y_axis);
  return {{"data", std::move(data)}, {"layout", std::move(layout)}};
}

json histogramFigure(const Histogram& histogram, const HistogramBins& bins) {
  // Each sample set is a filled step outline: (e0, 0), (e0, c0), (e1, c1), ...,
  // (e_n, c_{n-1}), (e_n, 0) with horizontal-then-vertical steps. Unlike bars, this draws the
  // same on linear and logarithmic x axes.
  const std::size_t bin_count = bins.edges.size() - 1;
  const bool overlay = histogram.series.size() > 1;
  json data = json::array();
  for (std::size_t s = 0; s < histogram.series.size(); ++s) {
    const std::vector<std::size_t>& counts = bins.counts[s];
    json x = json::array();
    json y = json::array();
    json bin_info = json::array();  // [low edge, high edge, count] for the hover text
    const auto add_point = [&](double x_value, std::size_t y_value, std::size_t bin) {
      x.push_back(x_value);
      y.push_back(y_value);
      bin_info.push_back({bins.edges[bin], bins.edges[bin + 1], counts[bin]});
    };
    add_point(bins.edges[0], 0, 0);
    for (std::size_t i = 0; i < bin_count; ++i) {
      add_point(bins.edges[i], counts[i], i);
    }
    add_point(bins.edges[bin_count], counts[bin_count - 1], bin_count - 1);
    add_point(bins.edges[bin_count], 0, bin_count - 1);
    // Translucent fills keep every outline visible where sample sets overlap.
    const char* color = kColorway[s % std::size(kColorway)];
    data.push_back({
        {"type", "scatter"},
        {"mode", "lines"},
        {"name", plotlyText(histogram.series[s].name)},
        {"x", std::move(x)},
        {"y", std::move(y)},
        {"customdata", std::move(bin_info)},
        {"line", {{"shape", "hv"}, {"width", 1.5}, {"color", color}}},
        {"fill", "tozeroy"},
        {"fillcolor", withAlpha(color, overlay ? 0.25 : 0.45)},
        {"hovertemplate",
         "[%{customdata[0]:.4g}, %{customdata[1]:.4g}): %{customdata[2]}<extra>%{fullData.name}</extra>"},
    });
  }
  json layout = baseLayout(kChartHeightPx, overlay);
  layout["xaxis"] = axisLayout(histogram.x_axis);
  Axis count_axis;
  count_axis.label = "Count";
  layout["yaxis"] = axisLayout(count_axis);
  layout["yaxis"]["rangemode"] = "tozero";
  return {{"data", std::move(data)}, {"layout", std::move(layout)}};
}

json heatMapFigure(const HeatMap& heat_map) {
  std::vector<double> z;
  z.reserve(heat_map.y.size() * heat_map.x.size());
  for (const std::vector<double>& row : heat_map.z) {
    z.insert(z.end(), row.begin(), row.end());
  }
  const std::string shape = std::to_string(heat_map.y.size()) + "," + std::to_string(heat_map.x.size());
  json trace = {
      {"type", "heatmap"},
      {"x", typedArray(heat_map.x)},
      {"y", typedArray(heat_map.y)},
      {"z", typedArray(z, shape.c_str())},
      {"hoverongaps", false},
      {"colorbar",
       {{"title",
         {{"text", plotlyText(labelWithUnit(heat_map.z_axis.label, heat_map.z_axis.unit))}, {"side", "right"}}},
        {"outlinewidth", 0}}},
  };
  if (heat_map.color_scale == ColorScale::kDiverging) {
    // ColorBrewer RdBu, blue for negative through white at zero to red for positive.
    trace["colorscale"] =
        json::array({{0.0, "#2166ac"}, {0.25, "#67a9cf"}, {0.5, "#f7f7f7"}, {0.75, "#ef8a62"}, {1.0, "#b2182b"}});
    trace["zmid"] = 0.0;
  } else {
    trace["colorscale"] = "Viridis";
  }
  json layout = baseLayout(kHeatMapHeightPx, false);
  layout["xaxis"] = axisLayout(heat_map.x_axis);
  layout["yaxis"] = axisLayout(heat_map.y_axis);
  layout["xaxis"]["showgrid"] = false;
  layout["yaxis"]["showgrid"] = false;
  return {{"data", json::array({std::move(trace)})}, {"layout", std::move(layout)}};
}

}  // namespace fullarm::reports::detail
