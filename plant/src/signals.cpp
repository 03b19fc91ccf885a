#include "fullarm/plant/signals.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fullarm::plant {

double signalValue(const SignalParams& s, double t) noexcept {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  switch (s.kind) {
    case SignalKind::kChirp: {
      const double tc = std::min(t, s.duration_s);
      const double phase = s.start_hz * tc + (s.stop_hz - s.start_hz) * tc * tc / (2.0 * s.duration_s);
      const double extra = t > s.duration_s ? s.stop_hz * (t - s.duration_s) : 0.0;
      return s.offset + s.amplitude * std::sin(kTwoPi * (phase + extra));
    }
    case SignalKind::kStep:
      return s.offset + (t >= s.step_time_s ? s.amplitude : 0.0);
    case SignalKind::kSine:
      return s.offset + s.amplitude * std::sin(kTwoPi * s.frequency_hz * t);
    case SignalKind::kMultisine: {
      // Schroeder (1970) low-crest-factor phases; peak normalised by sqrt(N/2) ~ crest factor.
      const int n = std::max(1, static_cast<int>(std::floor(s.stop_hz / s.start_hz)));
      double sum = 0.0;
      for (int k = 1; k <= n; ++k) {
        const double phi = -std::numbers::pi * k * (k - 1) / n;
        sum += std::cos(kTwoPi * k * s.start_hz * t + phi);
      }
      return s.offset + s.amplitude * sum / (1.5 * std::sqrt(0.5 * n));
    }
  }
  return 0.0;
}

SignalKind parseSignalKind(const std::string& name) {
  if (name == "chirp") return SignalKind::kChirp;
  if (name == "step") return SignalKind::kStep;
  if (name == "sine") return SignalKind::kSine;
  if (name == "multisine") return SignalKind::kMultisine;
  throw std::invalid_argument("unknown signal '" + name + "': expected chirp, step, sine, multisine or a .csv file");
}

double CommandTable::valueAt(std::size_t c, double t) const noexcept {
  const auto it = std::upper_bound(time_s.begin(), time_s.end(), t);
  const std::size_t row = it == time_s.begin() ? 0 : static_cast<std::size_t>(it - time_s.begin()) - 1;
  return columns[c][row];
}

CommandTable loadCommandCsv(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open the command CSV for reading");
  auto fail = [&](int line, const std::string& what) {
    throw std::runtime_error(file.string() + ":" + std::to_string(line) + ": " + what);
  };
  auto split = [](const std::string& text) {
    std::vector<std::string> cells;
    std::stringstream s(text);
    std::string cell;
    while (std::getline(s, cell, ',')) {
      cell.erase(0, cell.find_first_not_of(" \t\r"));
      cell.erase(cell.find_last_not_of(" \t\r") + 1);
      cells.push_back(cell);
    }
    return cells;
  };
  std::string text;
  if (!std::getline(in, text)) fail(1, "empty file: expected a header 'time_s,command'");
  const std::vector<std::string> header = split(text);
  if (header.size() < 2 || header[0] != "time_s" || !header[1].starts_with("command")) {
    fail(1, "bad header '" + text + "': expected 'time_s,command' (more columns: command_<joint>)");
  }
  CommandTable table;
  table.names.assign(header.begin() + 1, header.end());
  table.columns.resize(table.names.size());
  int line = 1;
  while (std::getline(in, text)) {
    ++line;
    if (text.find_first_not_of(" \t\r") == std::string::npos) continue;
    const std::vector<std::string> cells = split(text);
    if (cells.size() != header.size()) {
      fail(line, "expected " + std::to_string(header.size()) + " values, got " + std::to_string(cells.size()));
    }
    std::vector<double> values;
    for (const std::string& c : cells) {
      std::size_t used = 0;
      double v = 0.0;
      try {
        v = std::stod(c, &used);
      } catch (const std::exception&) {
        used = 0;
      }
      if (used != c.size() || c.empty() || !std::isfinite(v)) fail(line, "'" + c + "' is not a finite number");
      values.push_back(v);
    }
    if (!table.time_s.empty() && !(values[0] > table.time_s.back())) fail(line, "time_s must increase strictly");
    table.time_s.push_back(values[0]);
    for (std::size_t c = 0; c < table.columns.size(); ++c) table.columns[c].push_back(values[c + 1]);
  }
  if (table.time_s.empty()) fail(line, "no data rows");
  return table;
}

double normalisedRmsDifference(const std::vector<double>& reference, const std::vector<double>& other) {
  if (reference.empty() || reference.size() != other.size()) {
    throw std::invalid_argument("normalisedRmsDifference: expected two non-empty responses of equal length, got " +
                                std::to_string(reference.size()) + " and " + std::to_string(other.size()) + " samples");
  }
  double mean = 0.0;
  for (double v : reference) mean += v / static_cast<double>(reference.size());
  double diff = 0.0;
  double spread = 0.0;
  for (std::size_t i = 0; i < reference.size(); ++i) {
    diff += (reference[i] - other[i]) * (reference[i] - other[i]);
    spread += (reference[i] - mean) * (reference[i] - mean);
  }
  const bool constant =
      std::all_of(reference.begin(), reference.end(), [&reference](double v) { return v == reference.front(); });
  if (constant || !(spread > 0.0)) {
    throw std::invalid_argument(
        "normalisedRmsDifference: the reference response is constant (no spread to normalise by)");
  }
  return std::sqrt(diff / spread);
}

}  // namespace fullarm::plant
