#pragma once

// Renders a Report as one self-contained HTML page.

#include <string>

#include "fullarm/reports/report.hpp"

namespace fullarm::reports::detail {

// The caller has checked that the report has a verdict.
std::string renderHtml(const Report& report);

}  // namespace fullarm::reports::detail
