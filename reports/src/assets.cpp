#include "assets.hpp"

#include <cstddef>
#include <cstdint>

// Symbols defined by the generated report_assets.S (one blob per embedded file).
#define FULLARM_REPORTS_ASSET(name)                                                     \
  extern "C" __attribute__((visibility("hidden"))) const char fullarm_reports_##name[]; \
  extern "C" __attribute__((visibility("hidden"))) const std::uint64_t fullarm_reports_##name##_size;

FULLARM_REPORTS_ASSET(plotly_js)
FULLARM_REPORTS_ASSET(report_js)
FULLARM_REPORTS_ASSET(replay_js)
FULLARM_REPORTS_ASSET(report_css)

#undef FULLARM_REPORTS_ASSET

namespace fullarm::reports::detail {

std::string_view plotlyJs() noexcept {
  return {fullarm_reports_plotly_js, static_cast<std::size_t>(fullarm_reports_plotly_js_size)};
}

std::string_view reportJs() noexcept {
  return {fullarm_reports_report_js, static_cast<std::size_t>(fullarm_reports_report_js_size)};
}

std::string_view replayJs() noexcept {
  return {fullarm_reports_replay_js, static_cast<std::size_t>(fullarm_reports_replay_js_size)};
}

std::string_view reportCss() noexcept {
  return {fullarm_reports_report_css, static_cast<std::size_t>(fullarm_reports_report_css_size)};
}

}  // namespace fullarm::reports::detail
