#pragma once

/// @file
/// Tables for report.html.

#include <concepts>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <variant>
#include <vector>

namespace fullarm::reports {

/// One table cell: text, a floating-point number or an integer. Numbers are right-aligned and
/// floating-point numbers are shown with `Table::significant_digits`.
class Cell {
 public:
  /// The cell's value.
  using Value = std::variant<std::string, double, std::int64_t>;

  /// An empty text cell.
  Cell() = default;
  /// A text cell.
  Cell(std::string text) : value_(std::move(text)) {}  // NOLINT(google-explicit-constructor)
  /// A text cell.
  Cell(const char* text) : value_(std::string(text)) {}  // NOLINT(google-explicit-constructor)
  /// A floating-point cell; NaN is shown as "NaN".
  Cell(double number) : value_(number) {}  // NOLINT(google-explicit-constructor)
  /// An integer cell.
  template <std::signed_integral T>
  Cell(T number) : value_(static_cast<std::int64_t>(number)) {}  // NOLINT
  /// An integer cell (values above INT64_MAX are stored as floating point).
  template <std::unsigned_integral T>
  Cell(T number)  // NOLINT(google-explicit-constructor)
      : value_(static_cast<std::uint64_t>(number) <=
                       static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max())
                   ? Value(static_cast<std::int64_t>(number))
                   : Value(static_cast<double>(number))) {}
  /// Booleans are not cells: write the text you mean ("yes", "pass", ...).
  Cell(bool) = delete;

  /// The cell's value.
  const Value& value() const noexcept { return value_; }

 private:
  Value value_;
};

/// A table: a header row and data rows of equal width.
struct Table {
  /// Caption shown above the table.
  std::string caption{};
  /// Column headings; put the unit in the heading, e.g. "Peak force [N]". At least one.
  std::vector<std::string> columns{};
  /// Data rows, each with `columns.size()` cells.
  std::vector<std::vector<Cell>> rows{};
  /// Significant digits of floating-point cells (1 to 17).
  int significant_digits = 6;
};

}  // namespace fullarm::reports
