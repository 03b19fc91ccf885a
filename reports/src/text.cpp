#include "text.hpp"

#include <cmath>
#include <cstdio>
#include <ctime>
#include <stdexcept>

namespace fullarm::reports::detail {

Text& Text::operator<<(double number) {
  return *this << std::string_view(formatNumber(number, 17));
}

std::string escapeHtml(std::string_view text) {
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  for (const char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string jsonForScript(const nlohmann::json& value) {
  const std::string dumped = value.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
  // '<', '>' and '&' only occur inside JSON strings, where a \u escape means the same thing.
  std::string out;
  out.reserve(dumped.size());
  for (const char c : dumped) {
    switch (c) {
      case '<':
        out += "\\u003c";
        break;
      case '>':
        out += "\\u003e";
        break;
      case '&':
        out += "\\u0026";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string formatNumber(double value, int significant_digits) {
  if (std::isnan(value)) {
    return "NaN";
  }
  if (std::isinf(value)) {
    return value > 0 ? "inf" : "-inf";
  }
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*g", significant_digits, value);
  std::string text = buffer;
  // Large magnitudes below 1e9 read better as whole numbers than in exponent notation.
  const double magnitude = std::fabs(value);
  if (text.find('e') != std::string::npos && magnitude >= 1.0 && magnitude < 1e9) {
    std::snprintf(buffer, sizeof buffer, "%.0f", value);
    text = buffer;
  }
  return text;
}

std::string labelWithUnit(std::string_view label, std::string_view unit) {
  std::string out(label);
  if (!unit.empty()) {
    out += " [";
    out += unit;
    out += ']';
  }
  return out;
}

std::string formatUtc(std::chrono::system_clock::time_point time) {
  const std::time_t seconds = std::chrono::system_clock::to_time_t(time);
  std::tm utc{};
  gmtime_r(&seconds, &utc);
  char buffer[32];
  std::strftime(buffer, sizeof buffer, "%Y-%m-%dT%H:%M:%SZ", &utc);
  return buffer;
}

std::string encodeUrlPath(std::string_view path) {
  constexpr char kHex[] = "0123456789ABCDEF";
  std::string out;
  for (const char c : path) {
    const auto byte = static_cast<unsigned char>(c);
    const bool keep = (byte >= 'a' && byte <= 'z') || (byte >= 'A' && byte <= 'Z') || (byte >= '0' && byte <= '9') ||
                      c == '-' || c == '_' || c == '.' || c == '~' || c == '/';
    if (keep) {
      out += c;
    } else {
      out += '%';
      out += kHex[byte >> 4];
      out += kHex[byte & 0x0F];
    }
  }
  return out;
}

std::string describe(std::string_view kind, std::string_view title) {
  std::string out(kind);
  if (title.empty()) {
    out += " (untitled)";
  } else {
    out += " \"";
    out += title;
    out += '"';
  }
  return out;
}

void failInput(const std::string& what, const Text& problem) {
  throw std::invalid_argument((Text() << what << ": " << problem.str()).str());
}

void requireTitle(const std::string& what, const std::string& title) {
  if (title.empty()) {
    failInput(what, Text() << "a title is required");
  }
}

void checkValue(const std::string& what, const std::string& where, double value, bool log_axis, char axis_name) {
  if (std::isnan(value)) {
    return;
  }
  if (std::isinf(value)) {
    failInput(what, Text() << where << " is " << value << " (expected a finite value, or NaN for a missing value)");
  }
  if (log_axis && value <= 0.0) {
    failInput(what,
              Text() << where << " = " << value << " is not > 0, but the " << axis_name << " axis is logarithmic");
  }
}

}  // namespace fullarm::reports::detail
