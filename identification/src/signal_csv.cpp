#include "fullarm/identification/signal_csv.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

namespace fullarm::identification {
namespace {

std::string_view trim(std::string_view s) noexcept {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

std::vector<std::string_view> splitFields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = line.find(',', start);
    if (comma == std::string_view::npos) {
      fields.push_back(trim(line.substr(start)));
      return fields;
    }
    fields.push_back(trim(line.substr(start, comma - start)));
    start = comma + 1;
  }
}

std::string_view columnBase(std::string_view name) noexcept {
  const std::size_t underscore = name.rfind('_');
  return underscore == std::string_view::npos ? name : name.substr(0, underscore);
}

}  // namespace

namespace {
std::string locate(const std::string& source, std::size_t line, const std::string& message) {
  std::string text = source;
  if (line > 0) text.append(":").append(std::to_string(line));
  text.append(": ").append(message);
  return text;
}
}  // namespace

CsvFormatError::CsvFormatError(const std::string& source, std::size_t line, const std::string& message)
    : std::runtime_error(locate(source, line, message)), line_(line) {}

const std::vector<double>& SignalTable::column(std::string_view name) const {
  for (std::size_t c = 0; c < names.size(); ++c) {
    if (names[c] == name) return columns[c];
  }
  throw std::out_of_range("no column '" + std::string(name) + "'");
}

bool SignalTable::has(std::string_view name) const noexcept {
  for (const auto& n : names) {
    if (n == name) return true;
  }
  return false;
}

std::string_view columnUnit(std::string_view name) noexcept {
  const std::size_t underscore = name.rfind('_');
  return underscore == std::string_view::npos ? std::string_view{} : name.substr(underscore + 1);
}

void writeSignalCsv(const std::filesystem::path& file, const SignalTable& table) {
  if (table.names.size() != table.columns.size() || table.names.empty() || table.names.front() != "time_s") {
    throw std::invalid_argument("a signal table needs named columns, the first one time_s");
  }
  for (const auto& c : table.columns) {
    if (c.size() != table.rows()) throw std::invalid_argument("the columns of a signal table differ in length");
  }
  std::ofstream out(file);
  if (!out) throw std::runtime_error(file.string() + ": cannot be written");
  for (std::size_t c = 0; c < table.names.size(); ++c) out << (c > 0 ? "," : "") << table.names[c];
  out << '\n';
  char buffer[32];
  for (std::size_t r = 0; r < table.rows(); ++r) {
    for (std::size_t c = 0; c < table.columns.size(); ++c) {
      const int len = std::snprintf(buffer, sizeof buffer, "%.17g", table.columns[c][r]);
      if (c > 0) out << ',';
      out.write(buffer, len);
    }
    out << '\n';
  }
  if (!out) throw std::runtime_error(file.string() + ": write failed");
}

SignalTable parseSignalCsv(std::string_view text, const std::string& source, const std::vector<std::string>& required) {
  std::vector<std::string_view> lines;
  {
    std::size_t start = 0;
    while (start < text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string_view::npos) end = text.size();
      lines.push_back(text.substr(start, end - start));
      start = end + 1;
    }
  }
  // Trailing blank lines (a final newline, an editor's extra line) are not rows.
  while (!lines.empty() && trim(lines.back()).empty()) lines.pop_back();
  if (lines.empty()) throw CsvFormatError(source, 1, "empty file, expected a header line such as 'time_s,...'");

  SignalTable table;
  for (std::string_view name : splitFields(lines.front())) {
    if (name.empty()) throw CsvFormatError(source, 1, "empty column name in the header");
    if (table.has(name)) throw CsvFormatError(source, 1, "duplicate column '" + std::string(name) + "'");
    table.names.emplace_back(name);
  }
  std::vector<std::string> needed{"time_s"};
  for (const auto& r : required) {
    if (r != "time_s") needed.push_back(r);
  }
  for (const auto& want : needed) {
    if (table.has(want)) continue;
    for (const auto& have : table.names) {
      if (columnBase(have) == columnBase(want) && columnUnit(have) != columnUnit(want)) {
        throw CsvFormatError(source, 1,
                             "column '" + have + "' is in unit '" + std::string(columnUnit(have)) + "', expected '" +
                                 want + "' (unit '" + std::string(columnUnit(want)) + "')");
      }
    }
    throw CsvFormatError(source, 1, "missing column '" + want + "'");
  }
  const std::size_t width = table.names.size();
  table.columns.assign(width, {});
  std::size_t time_col = 0;
  while (table.names[time_col] != "time_s") ++time_col;

  for (std::size_t i = 1; i < lines.size(); ++i) {
    const std::size_t line_no = i + 1;
    const auto fields = splitFields(lines[i]);
    if (fields.size() != width) {
      throw CsvFormatError(source, line_no,
                           std::to_string(fields.size()) + " fields, the header has " + std::to_string(width));
    }
    for (std::size_t c = 0; c < width; ++c) {
      const std::string_view f = fields[c];
      double value = 0.0;
      const auto [ptr, ec] = std::from_chars(f.data(), f.data() + f.size(), value);
      if (f.empty() || ec != std::errc() || ptr != f.data() + f.size()) {
        throw CsvFormatError(source, line_no,
                             "column '" + table.names[c] + "': '" + std::string(f) + "' is not a number");
      }
      if (!std::isfinite(value)) {
        throw CsvFormatError(source, line_no,
                             "column '" + table.names[c] + "': '" + std::string(f) + "' is not finite");
      }
      table.columns[c].push_back(value);
    }
    const auto& t = table.columns[time_col];
    if (t.size() >= 2 && !(t.back() > t[t.size() - 2])) {
      std::ostringstream msg;
      msg.precision(17);
      msg << "time_s " << t.back() << " does not increase (previous row " << t[t.size() - 2] << ")";
      throw CsvFormatError(source, line_no, msg.str());
    }
  }
  if (table.rows() == 0) throw CsvFormatError(source, 1, "header but no data rows");
  if (time_col != 0) {
    std::swap(table.names[0], table.names[time_col]);
    std::swap(table.columns[0], table.columns[time_col]);
  }
  return table;
}

SignalTable readSignalCsv(const std::filesystem::path& file, const std::vector<std::string>& required) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CsvFormatError(file.string(), 0, "cannot be opened");
  std::ostringstream text;
  text << in.rdbuf();
  return parseSignalCsv(text.str(), file.string(), required);
}

}  // namespace fullarm::identification
