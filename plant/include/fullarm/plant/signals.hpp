#pragma once
/// @file
/// Command signals for plant experiments (docs/sources.md, Plant 4.2): linear chirp, step,
/// sine, Schroeder multisine, and a command table read from CSV.

#include <filesystem>
#include <string>
#include <vector>

namespace fullarm::plant {

enum class SignalKind { kChirp, kStep, kSine, kMultisine };

/// A generated command u(t) in the unit of the joint's command (V or N m).
struct SignalParams {
  SignalKind kind = SignalKind::kChirp;
  double amplitude = 1.0;
  double offset = 0.0;
  double start_hz = 0.5;      ///< chirp start / multisine fundamental
  double stop_hz = 80.0;      ///< chirp stop / multisine highest harmonic
  double duration_s = 5.0;    ///< chirp sweep time
  double frequency_hz = 1.0;  ///< sine
  double step_time_s = 0.1;   ///< step
};

/// u(t). Chirp: A sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))); multisine: Schroeder phases
/// phi_k = -pi k (k - 1) / N over harmonics k f0 <= f1, scaled to peak ~A. @rt
[[nodiscard]] double signalValue(const SignalParams& s, double t_s) noexcept;

/// Normalised RMS difference of two equally long responses: RMS(reference - other) over the RMS
/// spread of `reference` about its mean (dimensionless; the plant tests' "halving rtol changes
/// the chirp response by < 0.5 % RMS" is this ratio below 0.005).
/// @throws std::invalid_argument if the lengths differ, are zero, or `reference` is constant
[[nodiscard]] double normalisedRmsDifference(const std::vector<double>& reference, const std::vector<double>& other);

/// Parses "chirp", "step", "sine" or "multisine". @throws std::invalid_argument otherwise.
[[nodiscard]] SignalKind parseSignalKind(const std::string& name);

/// A command table from CSV: header `time_s,command` (extra columns: one per joint,
/// `command_<joint>`), strictly increasing time, finite values. Held between rows (ZOH).
struct CommandTable {
  std::vector<double> time_s;
  std::vector<std::vector<double>> columns;  ///< one vector per command column
  std::vector<std::string> names;
  /// Value of column c at t (last row at or before t; the first row before it). @rt
  [[nodiscard]] double valueAt(std::size_t c, double t_s) const noexcept;
};

/// @throws std::runtime_error naming the file, the line and what is wrong.
[[nodiscard]] CommandTable loadCommandCsv(const std::filesystem::path& file);

}  // namespace fullarm::plant
