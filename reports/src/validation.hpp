#pragma once

// Input checks behind Section::add*: each throws std::invalid_argument with a message that
// names the chart (or table) and says what was expected.

#include <string>
#include <string_view>

#include "fullarm/reports/charts.hpp"
#include "fullarm/reports/replay3d.hpp"
#include "fullarm/reports/table.hpp"

namespace fullarm::reports::detail {

// `kind` is "line chart" or "scatter chart".
void validateXyChart(const XyChart& chart, std::string_view kind);
void validateHeatMap(const HeatMap& heat_map);
void validateTable(const Table& table);
void validateReplay3d(const Replay3d& replay);

}  // namespace fullarm::reports::detail
