#pragma once

// Helpers for the fullarm::reports tests: temporary folders, file reading and a minimal look
// at the HTML (script elements and URL-bearing attributes).

#include <gtest/gtest.h>

#include "scratch_dir.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "fullarm/reports/report.hpp"

namespace fullarm::reports::test {

// The values of a chart array as Plotly reads it: a plain JSON array, or a typed array
// {"dtype": "f4" | "f8", "bdata": base64 of little-endian values}, decoded here with a decoder
// of its own (a lookup of each base64 character, no shared code with the writer).
inline std::vector<double> chartValues(const nlohmann::json& array) {
  std::vector<double> values;
  if (array.is_array()) {
    for (const nlohmann::json& v : array) {
      values.push_back(v.is_null() ? std::numeric_limits<double>::quiet_NaN() : v.get<double>());
    }
    return values;
  }
  const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const std::string text = array.at("bdata").get<std::string>();
  std::vector<unsigned char> bytes;
  std::uint32_t bits = 0;
  int bit_count = 0;
  for (const char c : text) {
    if (c == '=') break;
    const std::size_t index = alphabet.find(c);
    EXPECT_NE(index, std::string::npos) << "not base64: " << c;
    bits = (bits << 6) | static_cast<std::uint32_t>(index);
    bit_count += 6;
    if (bit_count >= 8) {
      bit_count -= 8;
      bytes.push_back(static_cast<unsigned char>((bits >> bit_count) & 0xFFU));
    }
  }
  const std::string dtype = array.at("dtype").get<std::string>();
  const std::size_t width = dtype == "f4" ? 4 : 8;
  EXPECT_TRUE(dtype == "f4" || dtype == "f8") << dtype;
  EXPECT_EQ(bytes.size() % width, 0U);
  for (std::size_t at = 0; at + width <= bytes.size(); at += width) {
    // Little-endian on the test machines (x86-64, arm64).
    if (width == 4) {
      float f = 0.0F;
      std::memcpy(&f, &bytes[at], 4);
      values.push_back(f);
    } else {
      double d = 0.0;
      std::memcpy(&d, &bytes[at], 8);
      values.push_back(d);
    }
  }
  return values;
}

// A fresh, empty folder for the running test.
inline std::filesystem::path freshTempDir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  const std::filesystem::path parent =
      std::filesystem::path(::testing::TempDir()) / ("fullarm_reports_" + std::to_string(::getpid()));
  std::filesystem::path dir = parent / (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  fullarm::test::ScratchRegistry::instance().add(parent);
  return dir;
}

inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  EXPECT_TRUE(in.good()) << "cannot open " << path;
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

inline std::string toLower(std::string text) {
  for (char& c : text) {
    if (c >= 'A' && c <= 'Z') {
      c = static_cast<char>(c - 'A' + 'a');
    }
  }
  return text;
}

inline std::size_t countOccurrences(const std::string& text, const std::string& needle) {
  std::size_t count = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) {
    ++count;
  }
  return count;
}

// The text of the JSON data block, as the browser's HTML parser would end it: at the first
// "</script" (any case) after its start tag.
inline std::string jsonDataBlock(const std::string& html) {
  const std::string start_tag = "<script type=\"application/json\" id=\"fullarm-report-data\">";
  const std::size_t start = html.find(start_tag);
  if (start == std::string::npos) {
    return {};
  }
  const std::size_t begin = start + start_tag.size();
  const std::size_t end = toLower(html).find("</script", begin);
  return html.substr(begin, end - begin);
}

// The HTML with the content of every script element removed (tags kept).
inline std::string withoutScriptContent(const std::string& html) {
  const std::string lower = toLower(html);
  std::string out;
  std::size_t at = 0;
  while (true) {
    const std::size_t open = lower.find("<script", at);
    if (open == std::string::npos) {
      break;
    }
    const std::size_t open_end = lower.find('>', open);
    const std::size_t close = lower.find("</script", open_end);
    out += html.substr(at, open_end + 1 - at);
    if (close == std::string::npos) {
      return out;
    }
    at = close;
  }
  out += html.substr(at);
  return out;
}

// Values of attributes that make a browser load or navigate to something (src, href, ...) in
// the markup outside script elements, plus CSS url(...) and @import references. A small tag
// scanner (std::regex trips GCC 12 -Wmaybe-uninitialized false positives under sanitizers).
inline std::vector<std::string> loadingReferences(const std::string& html) {
  constexpr std::string_view kLoadingAttributes[] = {"src",    "href", "srcset",     "action",    "formaction",
                                                     "poster", "data", "xlink:href", "background"};
  const std::string markup = withoutScriptContent(html);
  const std::string lower = toLower(markup);
  const auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f'; };
  std::vector<std::string> values;

  for (std::size_t at = lower.find('<'); at != std::string::npos; at = lower.find('<', at + 1)) {
    std::size_t i = at + 1;
    if (i >= lower.size() || lower[i] == '/' || lower[i] == '!') {
      continue;
    }
    while (i < lower.size() && !is_space(lower[i]) && lower[i] != '>') {
      ++i;  // tag name
    }
    while (i < lower.size() && lower[i] != '>') {
      while (i < lower.size() && (is_space(lower[i]) || lower[i] == '/')) {
        ++i;
      }
      const std::size_t name_begin = i;
      while (i < lower.size() && !is_space(lower[i]) && lower[i] != '=' && lower[i] != '>') {
        ++i;
      }
      const std::string name = lower.substr(name_begin, i - name_begin);
      while (i < lower.size() && is_space(lower[i])) {
        ++i;
      }
      if (i >= lower.size() || lower[i] != '=') {
        continue;
      }
      ++i;
      while (i < lower.size() && is_space(lower[i])) {
        ++i;
      }
      std::string value;
      if (i < lower.size() && (lower[i] == '"' || lower[i] == '\'')) {
        const char quote = lower[i];
        const std::size_t close = lower.find(quote, i + 1);
        const std::size_t value_end = close == std::string::npos ? lower.size() : close;
        value = markup.substr(i + 1, value_end - i - 1);
        i = value_end + 1;
      } else {
        const std::size_t value_begin = i;
        while (i < lower.size() && !is_space(lower[i]) && lower[i] != '>') {
          ++i;
        }
        value = markup.substr(value_begin, i - value_begin);
      }
      if (std::find(std::begin(kLoadingAttributes), std::end(kLoadingAttributes), name) !=
          std::end(kLoadingAttributes)) {
        values.push_back(value);
      }
    }
  }

  // CSS: url(...) with optional quotes, and @import "...".
  for (std::size_t at = lower.find("url("); at != std::string::npos; at = lower.find("url(", at + 4)) {
    std::size_t begin = at + 4;
    while (begin < lower.size() && (is_space(lower[begin]) || lower[begin] == '"' || lower[begin] == '\'')) {
      ++begin;
    }
    std::size_t end = begin;
    while (end < lower.size() && lower[end] != ')' && lower[end] != '"' && lower[end] != '\'') {
      ++end;
    }
    values.push_back(markup.substr(begin, end - begin));
  }
  for (std::size_t at = lower.find("@import"); at != std::string::npos; at = lower.find("@import", at + 7)) {
    const std::size_t begin = lower.find_first_of("\"'", at);
    if (begin == std::string::npos) {
      break;
    }
    const std::size_t end = lower.find(lower[begin], begin + 1);
    values.push_back(markup.substr(begin + 1, end - begin - 1));
  }
  return values;
}

// True if the reference would reach the network: an absolute URL with a scheme other than
// file:, data:, blob: or about:, or a scheme-relative "//host" URL.
inline bool isNetworkReference(const std::string& reference) {
  std::string value = toLower(reference);
  value.erase(0, value.find_first_not_of(" \t\r\n"));
  if (value.rfind("//", 0) == 0) {
    return true;
  }
  const std::size_t colon = value.find(':');
  const std::size_t slash = value.find('/');
  if (colon == std::string::npos || (slash != std::string::npos && slash < colon)) {
    return false;
  }
  const std::string scheme = value.substr(0, colon);
  return !(scheme == "file" || scheme == "data" || scheme == "blob" || scheme == "about");
}

// A report with one of everything, for tests that look at the output as a whole.
inline Report makeSampleReport() {
  Report report("demo", "Sample report");
  report.setVerdict(true, "All checks passed");
  report.addHeadlineNumber("gain_margin_db", "Gain margin", 8.1, "dB");
  report.addHeadlineNumber("settling_time_s", "Settling time", 0.125, "s");
  report.results()["gains"] = {{"k_p", 120.0}, {"k_d", 4.5}};
  Section& section = report.addSection("Results");
  section.addParagraph("A paragraph.");
  XyChart line;
  line.title = "Step response";
  line.x_axis = {"Time", "s", false};
  line.y_axis = {"Angle", "rad", false};
  line.series.push_back({"q1", {0.0, 0.1, 0.2}, {0.0, 0.5, 0.9}});  // short aggregate form must compile warning-free
  section.addLineChart(line);
  Table table;
  table.caption = "Gains";
  table.columns = {"Gain", "Value"};
  table.rows = {{"k_p", 120.0}, {"k_d", 4.5}};
  section.addTable(table);
  return report;
}

}  // namespace fullarm::reports::test
