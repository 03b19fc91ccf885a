#pragma once

// The 3D replay of a haptic run for its report: the arm's capsule links posed from the
// decimated joint angles (forward kinematics here, in C++), the scene's meshes, the adopted
// minima, penetrating links, contact torques and supervisor events.

#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/tri_mesh.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/reports/replay3d.hpp"

namespace fullarm::app {

/// Frames per second of run time the replay shows (the full-rate data stay in the LCM log).
inline constexpr double kReplayFrameRate_hz = 25.0;
/// The most frames a replay holds: runs longer than 120 s are shown at a lower frame rate, so
/// that the report stays small (a frame holds up to 128 minima, about 3.7 kB).
inline constexpr std::size_t kMaxReplayFrames = 3000;

/// A scene object's mesh for a replay, its vertices placed in the arm's world frame by `X_WO`.
[[nodiscard]] reports::ReplayMesh replayMesh(const std::string& name, const haptics::TriMesh& mesh,
                                             const Eigen::Isometry3d& X_WO);

/// Adds the arm's capsule links to `replay` (name and radius; links without geometry carry
/// nothing to draw) and returns their indices in the arm model, in the order added.
std::vector<int> addReplayCapsuleLinks(const arm::ArmModel& model, reports::Replay3d& replay);

/// The replay of run `r` of `session`, in the arm's world frame W, at `frame_rate_hz` (lower
/// when the run would need more than kMaxReplayFrames frames). A frame stands for the
/// ticks since the previous frame and is posed at its last tick; a link is marked
/// penetrating in a frame when it touched an object (telemetry link_penetration_mask) at any
/// of those ticks, so a touch shorter than a frame still shows.
[[nodiscard]] reports::Replay3d runReplay3d(const hil::RunResult& r, const hil::HilSession& session,
                                            double frame_rate_hz = kReplayFrameRate_hz);

/// Figures of the replay for summary.json: frame count and rate, and per link the time of its
/// first penetration in the telemetry (null: never).
[[nodiscard]] nlohmann::json replaySummary(const reports::Replay3d& replay, const hil::RunResult& r);

/// What the report of `fullarm replay` shows of a run, read back from its LCM log: per logged
/// tick the joint angles, valve commands, contact torques and per-link forces, distances and
/// penetration (hil::TickTelemetry fields of those names; t_s = tick x the loop period), the
/// adopted minima sets and the supervisor's events. Ticks without both their joint state and
/// their haptic status (a truncated log's last tick) are left out.
/// @throws hil::RunLogError for a corrupt log; hil::RecordError for a record out of bounds
[[nodiscard]] hil::RunResult runFromLog(const std::filesystem::path& log, const hil::HilSession& session);

}  // namespace fullarm::app
