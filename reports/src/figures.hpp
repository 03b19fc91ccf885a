#pragma once

// Plotly figures ({"data": [...], "layout": {...}}) for the validated chart types. Caller text
// that Plotly draws (names, axis titles, hover text) is HTML-escaped, because Plotly reads it
// as its own small HTML subset.

#include <nlohmann/json.hpp>

#include "fullarm/reports/charts.hpp"

namespace fullarm::reports::detail {

// `scatter` selects the default mode of SeriesMode::kAuto series (markers, else lines).
nlohmann::json xyFigure(const XyChart& chart, bool scatter);
nlohmann::json histogramFigure(const Histogram& histogram, const HistogramBins& bins);
nlohmann::json heatMapFigure(const HeatMap& heat_map);

}  // namespace fullarm::reports::detail
