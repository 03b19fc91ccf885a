#include "validation.hpp"

#include <cmath>
#include <limits>
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

namespace {

void checkFinite(const std::string& what, const Text& where, double value) {
  if (!std::isfinite(value)) failInput(what, Text() << where.str() << " is " << value << " (expected a finite number)");
}

}  // namespace

void validateReplay3d(const Replay3d& replay) {
  const std::string what = describe("3D replay", replay.title);
  requireTitle(what, replay.title);
  if (replay.links.empty()) failInput(what, Text() << "at least one link is required");
  if (replay.frames.empty()) failInput(what, Text() << "at least one frame is required");
  for (const ReplayLink& link : replay.links) {
    if (!(std::isfinite(link.radius_m) && link.radius_m > 0.0)) {
      failInput(what, Text() << "link \"" << link.name << "\" has radius " << link.radius_m
                             << " m (expected a finite number > 0)");
    }
  }
  if (!(std::isfinite(replay.torque_scale_nm) && replay.torque_scale_nm > 0.0)) {
    failInput(what, Text() << "torque_scale_nm is " << replay.torque_scale_nm << " (expected a finite number > 0)");
  }
  if (!(std::isfinite(replay.force_scale_n) && replay.force_scale_n > 0.0)) {
    failInput(what, Text() << "force_scale_n is " << replay.force_scale_n << " (expected a finite number > 0)");
  }
  for (const ReplayMesh& mesh : replay.meshes) {
    for (std::size_t v = 0; v < mesh.vertices_m.size(); ++v) {
      for (double c : mesh.vertices_m[v]) checkFinite(what, Text() << "mesh \"" << mesh.name << "\" vertex " << v, c);
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (std::uint32_t index : mesh.triangles[t]) {
        if (index >= mesh.vertices_m.size()) {
          failInput(what, Text() << "mesh \"" << mesh.name << "\" triangle " << t << " has vertex index "
                                 << static_cast<std::size_t>(index) << " (expected < " << mesh.vertices_m.size()
                                 << ")");
        }
      }
    }
  }
  double previous_t_s = -std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < replay.frames.size(); ++f) {
    const ReplayFrame& frame = replay.frames[f];
    checkFinite(what, Text() << "frame " << f << " time", frame.t_s);
    if (!(frame.t_s > previous_t_s)) {
      failInput(what, Text() << "frame " << f << " time " << frame.t_s << " s does not follow " << previous_t_s
                             << " s (expected strictly increasing times)");
    }
    previous_t_s = frame.t_s;
    if (frame.segments_m.size() != replay.links.size() || frame.penetrating.size() != replay.links.size()) {
      failInput(what, Text() << "frame " << f << " has " << frame.segments_m.size() << " segments and "
                             << frame.penetrating.size() << " penetration flags (expected one per link, "
                             << replay.links.size() << ")");
    }
    if (frame.torques_nm.size() != replay.joints.size()) {
      failInput(what, Text() << "frame " << f << " has " << frame.torques_nm.size()
                             << " torques (expected one per joint, " << replay.joints.size() << ")");
    }
    for (const std::array<double, 6>& segment : frame.segments_m) {
      for (double c : segment) checkFinite(what, Text() << "frame " << f << " segment coordinate", c);
    }
    for (double tau : frame.torques_nm) checkFinite(what, Text() << "frame " << f << " torque", tau);
    for (const ReplayMinimum& minimum : frame.minima) {
      for (std::size_t a = 0; a < 3; ++a) {
        checkFinite(what, Text() << "frame " << f << " minimum point", minimum.link_point_m[a]);
        checkFinite(what, Text() << "frame " << f << " minimum point", minimum.object_point_m[a]);
      }
      if (!(std::isfinite(minimum.force_n) && minimum.force_n >= 0.0)) {
        failInput(what, Text() << "frame " << f << " has a minimum with force " << minimum.force_n
                               << " N (expected a finite number >= 0)");
      }
    }
  }
  for (const ReplayEvent& event : replay.events)
    checkFinite(what, Text() << "event \"" << event.label << "\" time", event.t_s);
}

}  // namespace fullarm::reports::detail
