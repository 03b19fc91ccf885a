#pragma once

// Text helpers shared by the HTML and figure writers.

#include <chrono>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

namespace fullarm::reports::detail {

// Builds a message by appending (no operator+ chains: GCC 12 reports false -Wrestrict
// positives on those at -O2). Numbers: integers in full, doubles with formatNumber(v, 17).
class Text {
 public:
  Text& operator<<(std::string_view text) {
    out_.append(text);
    return *this;
  }
  Text& operator<<(char c) {
    out_.push_back(c);
    return *this;
  }
  Text& operator<<(std::size_t number) { return *this << std::string_view(std::to_string(number)); }
  Text& operator<<(int number) { return *this << std::string_view(std::to_string(number)); }
  Text& operator<<(double number);
  const std::string& str() const noexcept { return out_; }

 private:
  std::string out_;
};

// Escapes & < > " ' for HTML text and double-quoted attribute values.
std::string escapeHtml(std::string_view text);

// Serialises JSON for embedding in a <script type="application/json"> element: every '<', '>'
// and '&' becomes a \u escape, so no "</script" or "<!--" can appear. Invalid UTF-8 is
// replaced by U+FFFD.
std::string jsonForScript(const nlohmann::json& value);

// A number for people: `significant_digits` significant digits, plain notation for
// magnitudes from 1e-4 to below 1e9 (up to the digits needed), "NaN", "inf", "-inf".
std::string formatNumber(double value, int significant_digits);

// "label [unit]", or "label" if unit is empty.
std::string labelWithUnit(std::string_view label, std::string_view unit);

// ISO-8601 UTC with whole seconds: "2025-01-31T14:05:09Z".
std::string formatUtc(std::chrono::system_clock::time_point time);

// Percent-encodes a relative path for an href attribute (keeps unreserved characters and '/').
std::string encodeUrlPath(std::string_view path);

// Input checks of charts and tables: `kind "title"` for messages (e.g. line chart "Bode
// magnitude"), and the std::invalid_argument they throw ("<what>: <problem>").
std::string describe(std::string_view kind, std::string_view title);
[[noreturn]] void failInput(const std::string& what, const Text& problem);
// Throws unless `title` is set.
void requireTitle(const std::string& what, const std::string& title);
// One value of a series axis: NaN (missing) is fine, infinity is not, and on a logarithmic
// axis the value must be > 0. `where` says which value, `axis_name` which axis ('x', 'y').
void checkValue(const std::string& what, const std::string& where, double value, bool log_axis, char axis_name);
}  // namespace fullarm::reports::detail
