#pragma once

// The JSON a 3D replay is stored as in report.html (read by reports/assets/replay3d.js; the
// layout is documented in docs/reports.md).

#include <nlohmann/json.hpp>

#include "fullarm/reports/replay3d.hpp"

namespace fullarm::reports::detail {

// The replay, validated by the caller, with its binary arrays base64-encoded.
nlohmann::json replayJson(const Replay3d& replay);

}  // namespace fullarm::reports::detail
