#include "validation.hpp"

#include <cmath>
#include <stdexcept>

#include "text.hpp"

namespace fullarm::reports::detail {

void validateXyChart(const XyChart& chart, std::string_view kind) {
  const std::string what = describe(kind, chart.title);
  requireTitle(what, chart.title);
  if (chart.series.empty()) {
    failInput(what, Text() << "at least one series is required");
  }
  for (const Series& series : chart.series) {
    const std::string name = (Text() << "series \"" << series.name << '"').str();
    if (series.x.size() != series.y.size()) {
      failInput(what, Text() << name << " has " << series.x.size() << " x values but " << series.y.size()
                             << " y values (expected the same number)");
    }
    if (!series.point_labels.empty() && series.point_labels.size() != series.x.size()) {
      failInput(what, Text() << name << " has " << series.point_labels.size() << " point labels for " << series.x.size()
                             << " points (expected none or one per point)");
    }
    for (std::size_t i = 0; i < series.x.size(); ++i) {
      checkValue(what, (Text() << name << " x[" << i << ']').str(), series.x[i], chart.x_axis.log, 'x');
      checkValue(what, (Text() << name << " y[" << i << ']').str(), series.y[i], chart.y_axis.log, 'y');
    }
  }
}

void validateHeatMap(const HeatMap& heat_map) {
  const std::string what = describe("heat map", heat_map.title);
  requireTitle(what, heat_map.title);
  const auto check_coordinates = [&](const std::vector<double>& values, const Axis& axis, char axis_name) {
    if (values.empty()) {
      failInput(what, Text() << axis_name << " is empty (expected at least one "
                             << (axis_name == 'x' ? "column" : "row") << " centre)");
    }
    for (std::size_t i = 0; i < values.size(); ++i) {
      const std::string where = (Text() << axis_name << '[' << i << ']').str();
      if (!std::isfinite(values[i])) {
        failInput(what, Text() << where << " is " << values[i] << " (expected a finite value)");
      }
      checkValue(what, where, values[i], axis.log, axis_name);
    }
    if (values.size() >= 2) {
      const bool increasing = values[1] > values[0];
      for (std::size_t i = 1; i < values.size(); ++i) {
        if (increasing ? !(values[i] > values[i - 1]) : !(values[i] < values[i - 1])) {
          failInput(what, Text() << axis_name << " is not strictly monotonic at index " << i << " (" << values[i - 1]
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
    failInput(what, Text() << "z has " << heat_map.z.size() << " rows; " << expected);
  }
  for (std::size_t row = 0; row < heat_map.z.size(); ++row) {
    const std::vector<double>& values = heat_map.z[row];
    if (values.size() != heat_map.x.size()) {
      failInput(what, Text() << "z row " << row << " has " << values.size() << " columns; " << expected);
    }
    for (std::size_t column = 0; column < values.size(); ++column) {
      if (std::isinf(values[column])) {
        failInput(what, Text() << "z[" << row << "][" << column << "] is " << values[column]
                               << " (expected a finite value, or NaN for a cell without a value)");
      }
    }
  }
}

void validateTable(const Table& table) {
  const std::string what = describe("table", table.caption);
  if (table.columns.empty()) {
    failInput(what, Text() << "at least one column is required");
  }
  if (table.significant_digits < 1 || table.significant_digits > 17) {
    failInput(what, Text() << "significant_digits is " << table.significant_digits << " (expected 1 to 17)");
  }
  for (std::size_t row = 0; row < table.rows.size(); ++row) {
    if (table.rows[row].size() != table.columns.size()) {
      failInput(what, Text() << "row " << row << " has " << table.rows[row].size() << " cells (expected "
                             << table.columns.size() << ", one per column)");
    }
  }
}

}  // namespace fullarm::reports::detail
