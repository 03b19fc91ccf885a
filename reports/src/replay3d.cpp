// The 3D replay: validation, the compact binary encoding and its JSON for report.html.
#include "fullarm/reports/replay3d.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

#include "replay3d_json.hpp"
#include "text.hpp"
#include "validation.hpp"

namespace fullarm::reports {

std::string encodeBase64(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const auto b0 = static_cast<unsigned char>(bytes[i]);
    const auto b1 = static_cast<unsigned char>(bytes[i + 1]);
    const auto b2 = static_cast<unsigned char>(bytes[i + 2]);
    out += kAlphabet[b0 >> 2];
    out += kAlphabet[((b0 & 0x03) << 4) | (b1 >> 4)];
    out += kAlphabet[((b1 & 0x0f) << 2) | (b2 >> 6)];
    out += kAlphabet[b2 & 0x3f];
  }
  const std::size_t rest = bytes.size() - i;
  if (rest > 0) {
    const auto b0 = static_cast<unsigned char>(bytes[i]);
    const unsigned b1 = rest > 1 ? static_cast<unsigned char>(bytes[i + 1]) : 0U;
    out += kAlphabet[b0 >> 2];
    out += kAlphabet[((b0 & 0x03) << 4) | (b1 >> 4)];
    out += rest > 1 ? kAlphabet[(b1 & 0x0f) << 2] : '=';
    out += '=';
  }
  return out;
}

QuantisedPositions quantisePositions(const std::vector<std::array<double, 3>>& vertices_m) {
  QuantisedPositions out;
  if (vertices_m.empty()) {
    out.scale_m = {1.0, 1.0, 1.0};
    return out;
  }
  std::array<double, 3> low = vertices_m.front();
  std::array<double, 3> high = low;
  for (const std::array<double, 3>& v : vertices_m) {
    for (std::size_t a = 0; a < 3; ++a) {
      low[a] = std::min(low[a], v[a]);
      high[a] = std::max(high[a], v[a]);
    }
  }
  for (std::size_t a = 0; a < 3; ++a) {
    out.origin_m[a] = low[a];
    out.scale_m[a] = high[a] > low[a] ? (high[a] - low[a]) / 65535.0 : 1.0;
  }
  out.q.reserve(vertices_m.size() * 3);
  for (const std::array<double, 3>& v : vertices_m) {
    for (std::size_t a = 0; a < 3; ++a) {
      const double steps = std::round((v[a] - out.origin_m[a]) / out.scale_m[a]);
      out.q.push_back(static_cast<std::uint16_t>(std::clamp(steps, 0.0, 65535.0)));
    }
  }
  return out;
}

namespace detail {
namespace {

static_assert(std::endian::native == std::endian::little,
              "the replay's typed arrays are little-endian, as JavaScript reads them on every browser");

template <typename T>
void appendBytes(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

void checkFinite(const std::string& what, const Text& where, double value) {
  if (!std::isfinite(value)) failInput(what, Text() << where.str() << " is " << value << " (expected a finite number)");
}

}  // namespace

void validateReplay3d(const Replay3d& replay) {
  const std::string what = describe("3D replay", replay.title);
  requireTitle(what, replay.title);
  if (replay.links.empty()) failInput(what, Text() << "at least one link is required");
  if (replay.frames.empty()) failInput(what, Text() << "at least one frame is required");
  for (const ReplayLink& link : replay.links) {
    if (!(std::isfinite(link.radius_m) && link.radius_m > 0.0)) {
      failInput(what, Text() << "link \"" << link.name << "\" has radius " << link.radius_m
                             << " m (expected a finite number > 0)");
    }
  }
  if (!(std::isfinite(replay.torque_scale_nm) && replay.torque_scale_nm > 0.0)) {
    failInput(what, Text() << "torque_scale_nm is " << replay.torque_scale_nm << " (expected a finite number > 0)");
  }
  if (!(std::isfinite(replay.force_scale_n) && replay.force_scale_n > 0.0)) {
    failInput(what, Text() << "force_scale_n is " << replay.force_scale_n << " (expected a finite number > 0)");
  }
  for (const ReplayMesh& mesh : replay.meshes) {
    for (std::size_t v = 0; v < mesh.vertices_m.size(); ++v) {
      for (double c : mesh.vertices_m[v]) checkFinite(what, Text() << "mesh \"" << mesh.name << "\" vertex " << v, c);
    }
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
      for (std::uint32_t index : mesh.triangles[t]) {
        if (index >= mesh.vertices_m.size()) {
          failInput(what, Text() << "mesh \"" << mesh.name << "\" triangle " << t << " has vertex index " << static_cast<std::size_t>(index)
                                 << " (expected < " << mesh.vertices_m.size() << ")");
        }
      }
    }
  }
  double previous_t_s = -std::numeric_limits<double>::infinity();
  for (std::size_t f = 0; f < replay.frames.size(); ++f) {
    const ReplayFrame& frame = replay.frames[f];
    checkFinite(what, Text() << "frame " << f << " time", frame.t_s);
    if (!(frame.t_s > previous_t_s)) {
      failInput(what, Text() << "frame " << f << " time " << frame.t_s << " s does not follow " << previous_t_s
                             << " s (expected strictly increasing times)");
    }
    previous_t_s = frame.t_s;
    if (frame.segments_m.size() != replay.links.size() || frame.penetrating.size() != replay.links.size()) {
      failInput(what, Text() << "frame " << f << " has " << frame.segments_m.size() << " segments and "
                             << frame.penetrating.size() << " penetration flags (expected one per link, "
                             << replay.links.size() << ")");
    }
    if (frame.torques_nm.size() != replay.joints.size()) {
      failInput(what, Text() << "frame " << f << " has " << frame.torques_nm.size() << " torques (expected one per joint, "
                             << replay.joints.size() << ")");
    }
    for (const std::array<double, 6>& segment : frame.segments_m) {
      for (double c : segment) checkFinite(what, Text() << "frame " << f << " segment coordinate", c);
    }
    for (double tau : frame.torques_nm) checkFinite(what, Text() << "frame " << f << " torque", tau);
    for (const ReplayMinimum& minimum : frame.minima) {
      for (std::size_t a = 0; a < 3; ++a) {
        checkFinite(what, Text() << "frame " << f << " minimum point", minimum.link_point_m[a]);
        checkFinite(what, Text() << "frame " << f << " minimum point", minimum.object_point_m[a]);
      }
      if (!(std::isfinite(minimum.force_n) && minimum.force_n >= 0.0)) {
        failInput(what, Text() << "frame " << f << " has a minimum with force " << minimum.force_n
                               << " N (expected a finite number >= 0)");
      }
    }
  }
  for (const ReplayEvent& event : replay.events) checkFinite(what, Text() << "event \"" << event.label << "\" time", event.t_s);
}

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

}  // namespace detail
}  // namespace fullarm::reports
