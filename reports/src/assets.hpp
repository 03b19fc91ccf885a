#pragma once

// Files embedded into the library at build time (see reports/CMakeLists.txt and the
// generated report_assets.S).

#include <string_view>

namespace fullarm::reports::detail {

// plotly.min.js from node_modules/plotly.js-dist-min, byte for byte.
std::string_view plotlyJs() noexcept;
// reports/assets/report.js: draws every [data-chart] element.
std::string_view reportJs() noexcept;
// three.js and reports/assets/replay3d.js, bundled by esbuild: draws every [data-replay3d]
// element (only inlined into reports that hold a 3D replay).
std::string_view replayJs() noexcept;
// reports/assets/report.css.
std::string_view reportCss() noexcept;

}  // namespace fullarm::reports::detail
