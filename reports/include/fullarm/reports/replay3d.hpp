#pragma once

/// @file
/// A 3D replay for report.html: the arm's capsule links posed frame by frame, the scene's
/// meshes, the minima as lines coloured by force, penetrating links highlighted, joint torque
/// bars and the supervisor's events on a time slider (drawn with the inlined three.js).
///
/// The replay is plain data. Poses are computed by the caller (forward kinematics in C++):
/// each frame stores every link's capsule segment in the world frame, so the page needs no
/// kinematics. Section::addReplay3d() validates it; the report stores the scene meshes once
/// (positions quantised to 16 bits over their bounding box, triangle indices as 32-bit
/// integers) and the per-frame arrays as 32-bit floats, all base64-encoded (docs/reports.md).

#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace fullarm::reports {

/// One static triangle mesh of the scene, in the replay's world frame.
struct ReplayMesh {
  std::string name{};
  /// Vertex positions [m].
  std::vector<std::array<double, 3>> vertices_m{};
  /// Vertex indices, three per triangle.
  std::vector<std::array<std::uint32_t, 3>> triangles{};
};

/// One capsule link of the arm.
struct ReplayLink {
  std::string name{};
  double radius_m = 0.0;  ///< > 0
};

/// One minimum shown in a frame: a line from the link point to the object point.
struct ReplayMinimum {
  std::array<double, 3> link_point_m{};    ///< world frame [m]
  std::array<double, 3> object_point_m{};  ///< world frame [m]
  double force_n = 0.0;                    ///< colours the line (>= 0)
};

/// One supervisor event, marked on the time slider.
struct ReplayEvent {
  double t_s = 0.0;
  std::string label{};
  bool trip = false;  ///< a trip (drawn red) or an informational event
};

/// One displayed frame.
struct ReplayFrame {
  double t_s = 0.0;
  /// Per link: the capsule segment {from x, y, z, to x, y, z} in the world frame [m].
  std::vector<std::array<double, 6>> segments_m{};
  /// Per link: true when the link touches or penetrates an object in this frame.
  std::vector<bool> penetrating{};
  /// Per joint (Replay3d::joints): the torque shown as a bar [N·m].
  std::vector<double> torques_nm{};
  std::vector<ReplayMinimum> minima{};
};

/// The whole replay.
struct Replay3d {
  /// Title shown above the view (required, also used in error messages).
  std::string title{};
  /// Static scene meshes, stored once.
  std::vector<ReplayMesh> meshes{};
  /// The arm's capsule links (at least one).
  std::vector<ReplayLink> links{};
  /// Names of the torque bars.
  std::vector<std::string> joints{};
  /// Full scale of the torque bars [N·m] (> 0).
  double torque_scale_nm = 1.0;
  /// Force that gets the hottest colour [N] (> 0).
  double force_scale_n = 1.0;
  /// At least one frame; times strictly increasing.
  std::vector<ReplayFrame> frames{};
  std::vector<ReplayEvent> events{};
  /// Optional note shown under the view.
  std::string caption{};
};

/// Standard base64 (RFC 4648, with padding) of `bytes`.
[[nodiscard]] std::string encodeBase64(std::string_view bytes);

/// A mesh's vertices quantised to 16 bits per axis over its axis-aligned bounding box:
/// vertex = origin + q * scale, componentwise, with q in 0..65535.
struct QuantisedPositions {
  std::array<double, 3> origin_m{};
  std::array<double, 3> scale_m{};  ///< bounding-box size / 65535 (1 for a flat axis)
  std::vector<std::uint16_t> q{};   ///< three per vertex
};

/// Quantises `vertices_m` (error at most half a step, scale / 2, per axis).
[[nodiscard]] QuantisedPositions quantisePositions(const std::vector<std::array<double, 3>>& vertices_m);

}  // namespace fullarm::reports
