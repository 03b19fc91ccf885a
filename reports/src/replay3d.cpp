// The 3D replay's compact binary encoding: base64 and 16-bit quantised positions.
#include "fullarm/reports/replay3d.hpp"

#include <algorithm>
#include <cmath>

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

}  // namespace fullarm::reports
