#pragma once

// Files embedded into the library at build time (see reports/CMakeLists.txt and the
// generated report_assets.S).

#include <string_view>

namespace fullarm::reports::detail {

// plotly.min.js from node_modules/plotly.js-dist-min, byte for byte.
std::string_view plotlyJs() noexcept;
// reports/assets/report.js: draws every [data-chart] element.
std::string_view reportJs() noexcept;
// reports/assets/report.css.
std::string_view reportCss() noexcept;

}  // namespace fullarm::reports::detail
