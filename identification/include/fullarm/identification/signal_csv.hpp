#pragma once
/// @file
/// Signals and experiment logs as CSV: a header of column names, each carrying its unit after
/// the last underscore (`time_s`, `excitation_v`, `q_rad`, `tau_measured_nm`), then one row per
/// sample. Reading is strict: a missing column, a column in another unit, a duplicate column, a
/// short or long row, a field that is not a number, a NaN or infinity, time that does not
/// strictly increase, or an empty file is an error naming the file, the line and the value.

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace fullarm::identification {

/// The columns of a closed-loop experiment log, in order.
inline const std::vector<std::string> kExperimentColumns{"time_s", "excitation_v", "command_v", "q_rad",
                                                         "tau_measured_nm"};
/// The driven joint's chamber pressures [Pa, gauge], logged after kExperimentColumns where the
/// device reads them.
inline const std::vector<std::string> kPressureColumns{"pressure_a_pa", "pressure_b_pa"};

/// A malformed CSV file; what() names the file and the line (1-based; 0 for the file as a whole).
class CsvFormatError : public std::runtime_error {
 public:
  CsvFormatError(const std::string& source, std::size_t line, const std::string& message);
  [[nodiscard]] std::size_t line() const noexcept { return line_; }

 private:
  std::size_t line_;
};

/// Named columns of equal length; the first is `time_s`.
struct SignalTable {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;

  [[nodiscard]] std::size_t rows() const noexcept { return columns.empty() ? 0 : columns.front().size(); }
  /// The column called `name`. @throws std::out_of_range naming it when absent
  [[nodiscard]] const std::vector<double>& column(std::string_view name) const;
  /// True when a column is called `name`.
  [[nodiscard]] bool has(std::string_view name) const noexcept;
};

/// Writes the table (17 significant digits: reading it back gives the same doubles).
/// @throws std::invalid_argument for columns of unequal length or a first column other than
///   `time_s`; std::runtime_error naming the file when it cannot be written
void writeSignalCsv(const std::filesystem::path& file, const SignalTable& table);

/// Parses CSV text; `source` names it in errors. `required` columns must be present (in any
/// order, beside others); `time_s` always is.
/// @throws CsvFormatError naming `source`, the line and the offending value
[[nodiscard]] SignalTable parseSignalCsv(std::string_view text, const std::string& source,
                                         const std::vector<std::string>& required);

/// Reads a CSV file (see parseSignalCsv).
/// @throws CsvFormatError (also when the file cannot be opened)
[[nodiscard]] SignalTable readSignalCsv(const std::filesystem::path& file, const std::vector<std::string>& required);

/// The unit of a column name: the text after its last underscore ("" when it has none).
[[nodiscard]] std::string_view columnUnit(std::string_view name) noexcept;

}  // namespace fullarm::identification
