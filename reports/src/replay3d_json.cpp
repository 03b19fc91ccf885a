// The JSON a 3D replay is stored as in report.html: the binary arrays little-endian, base64.
#include "replay3d_json.hpp"

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>

namespace fullarm::reports::detail {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the replay's typed arrays are little-endian, as JavaScript reads them on every browser");

template <typename T>
void appendBytes(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

}  // namespace

nlohmann::json replayJson(const Replay3d& replay) {
  using nlohmann::json;
  json links = json::array();
  for (const ReplayLink& link : replay.links) links.push_back({{"name", link.name}, {"radius_m", link.radius_m}});
  json meshes = json::array();
  for (const ReplayMesh& mesh : replay.meshes) {
    const QuantisedPositions positions = quantisePositions(mesh.vertices_m);
    std::string position_bytes;
    position_bytes.reserve(positions.q.size() * 2);
    for (std::uint16_t q : positions.q) appendBytes(position_bytes, q);
    std::string index_bytes;
    index_bytes.reserve(mesh.triangles.size() * 12);
    for (const std::array<std::uint32_t, 3>& triangle : mesh.triangles) {
      for (std::uint32_t index : triangle) appendBytes(index_bytes, index);
    }
    meshes.push_back({{"name", mesh.name},
                      {"origin_m", positions.origin_m},
                      {"scale_m", positions.scale_m},
                      {"positions_u16", encodeBase64(position_bytes)},
                      {"indices_u32", encodeBase64(index_bytes)}});
  }
  std::string times;
  std::string segments;
  std::string penetrating;
  std::string torques;
  std::string minima_offsets;
  std::string minima;
  std::uint32_t minima_count = 0;
  for (const ReplayFrame& frame : replay.frames) {
    appendBytes(times, frame.t_s);
    for (const std::array<double, 6>& segment : frame.segments_m) {
      for (double c : segment) appendBytes(segments, static_cast<float>(c));
    }
    for (bool p : frame.penetrating) appendBytes(penetrating, static_cast<std::uint8_t>(p ? 1 : 0));
    for (double tau : frame.torques_nm) appendBytes(torques, static_cast<float>(tau));
    appendBytes(minima_offsets, minima_count);
    for (const ReplayMinimum& minimum : frame.minima) {
      for (double c : minimum.link_point_m) appendBytes(minima, static_cast<float>(c));
      for (double c : minimum.object_point_m) appendBytes(minima, static_cast<float>(c));
      appendBytes(minima, static_cast<float>(minimum.force_n));
      ++minima_count;
    }
  }
  appendBytes(minima_offsets, minima_count);
  json events = json::array();
  for (const ReplayEvent& event : replay.events) {
    events.push_back({{"t_s", event.t_s}, {"label", event.label}, {"trip", event.trip}});
  }
  return json{{"title", replay.title},
              {"links", links},
              {"joints", replay.joints},
              {"torque_scale_nm", replay.torque_scale_nm},
              {"force_scale_n", replay.force_scale_n},
              {"meshes", meshes},
              {"frame_count", replay.frames.size()},
              {"t_f64", encodeBase64(times)},
              {"segments_f32", encodeBase64(segments)},
              {"penetrating_u8", encodeBase64(penetrating)},
              {"torques_f32", encodeBase64(torques)},
              {"minima_offsets_u32", encodeBase64(minima_offsets)},
              {"minima_f32", encodeBase64(minima)},
              {"events", events}};
}

}  // namespace fullarm::reports::detail
