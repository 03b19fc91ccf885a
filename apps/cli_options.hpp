#pragma once
// The declared options of the `fullarm` program: each option is declared once, where its
// subcommand defines it, with its kind and valid range; the declaration installs the CLI11
// validator that enforces it and records the option in an OptionTable. The table is what
// tests/apps/option_table_test.cpp feeds bad values to, option by option, so an option declared
// here is covered without anyone adding a test for it; an option added with CLI11's own
// add_option instead fails that test (every option of the program must be in the table).

#include <CLI/CLI.hpp>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace fullarm::app {

/// What an option takes.
enum class OptionKind {
  kNumber,      ///< a finite real number within [min, max]
  kInteger,     ///< an integer within [min, max]
  kList,        ///< comma-separated names: none empty, none repeated
  kNumberList,  ///< comma- or space-separated finite real numbers (at least one)
  kChoice,      ///< one of a fixed set of words
  kName,        ///< one name the command checks against its model or files (a joint, a signal): not empty
  kFile,        ///< an existing file
  kFolder,      ///< an output folder (created if missing)
  kFlag,        ///< no value
};

/// One declared option.
struct OptionSpec {
  std::string command;  ///< the subcommand path, e.g. "plant simulate"
  std::string name;     ///< the long name, e.g. "--duration"
  OptionKind kind = OptionKind::kFlag;
  double min = 0.0;                  ///< kNumber, kInteger: the smallest valid value
  double max = 0.0;                  ///< kNumber, kInteger: the largest valid value
  std::string unit;                  ///< kNumber: the unit, as the help shows it ("s", "Hz"; may be empty)
  std::vector<std::string> choices;  ///< kChoice
};

/// Every declared option of the program, in declaration order.
class OptionTable {
 public:
  /// Records `spec`; returns it, for the declarer to fill in (valid until the next add()).
  OptionSpec& add(OptionSpec spec) {
    specs_.push_back(std::move(spec));
    return specs_.back();
  }
  [[nodiscard]] const std::vector<OptionSpec>& specs() const noexcept { return specs_; }

 private:
  std::vector<OptionSpec> specs_;
};

/// An inclusive range of valid values with its unit ("" for a pure number).
struct NumberRange {
  double min;
  double max;
  std::string unit;
};

/// Declares the options of one subcommand: each call adds a CLI11 option whose validator rejects
/// NaN, infinities and values outside the declared range with a message that names the option
/// and what was expected, and records the option in the table.
class OptionDeclarer {
 public:
  OptionDeclarer(CLI::App& command, OptionTable& table);

  /// A real number in `range` (NaN and infinities are always refused).
  CLI::Option* number(const std::string& name, double& value, const std::string& description, NumberRange range);
  CLI::Option* number(const std::string& name, std::optional<double>& value, const std::string& description,
                      NumberRange range);
  /// An integer in [min, max].
  CLI::Option* integer(const std::string& name, int& value, const std::string& description, std::int64_t min,
                       std::int64_t max);
  CLI::Option* integer(const std::string& name, std::optional<int>& value, const std::string& description,
                       std::int64_t min, std::int64_t max);
  CLI::Option* integer(const std::string& name, std::int64_t& value, const std::string& description, std::int64_t min,
                       std::int64_t max);
  CLI::Option* integer(const std::string& name, std::optional<std::int64_t>& value, const std::string& description,
                       std::int64_t min, std::int64_t max);
  CLI::Option* integer(const std::string& name, std::uint64_t& value, const std::string& description, std::int64_t min,
                       std::int64_t max);
  /// Comma-separated names (joints): at least one, none empty, none repeated.
  CLI::Option* list(const std::string& name, std::vector<std::string>& values, const std::string& description);
  /// The same kept as the text given (checked the same way).
  CLI::Option* list(const std::string& name, std::string& text, const std::string& description);
  /// Comma- or space-separated finite numbers, at least one (a joint vector; the command checks
  /// the count and each joint's range against its model).
  CLI::Option* numberList(const std::string& name, std::string& text, const std::string& description);
  /// One name, not empty (the command checks it against its model or files).
  CLI::Option* name(const std::string& option, std::string& value, const std::string& description);
  /// One of `choices`.
  CLI::Option* choice(const std::string& name, std::string& value, const std::string& description,
                      std::vector<std::string> choices);
  /// An existing file.
  CLI::Option* file(const std::string& name, std::string& path, const std::string& description);
  /// One or more existing files.
  CLI::Option* files(const std::string& name, std::vector<std::string>& paths, const std::string& description);
  /// An output folder (not empty).
  CLI::Option* folder(const std::string& name, std::string& path, const std::string& description);
  /// A flag (no value). `name` may hold CLI11's alternatives ("--a,!--no-a").
  CLI::Option* flag(const std::string& name, bool& value, const std::string& description);

 private:
  OptionSpec& record(const std::string& name, OptionKind kind);

  CLI::App& command_;
  OptionTable& table_;
  std::string path_;
};

/// The subcommand path of `command` ("plant simulate"): its name and its parents' up to, not
/// including, the program.
[[nodiscard]] std::string commandPath(const CLI::App& command);

/// Splits "EB, WR" at commas (spaces around names dropped; empty entries kept as "").
[[nodiscard]] std::vector<std::string> splitList(const std::string& text);

}  // namespace fullarm::app
