#pragma once

/// @file
/// The output folder of a fullarm subcommand: summary.json and a self-contained report.html.
///
/// @code
/// fullarm::reports::Report report("tune", "Admittance gains for joint 2");
/// report.setVerdict(true, "Stable with 8.1 dB gain margin");
/// report.addHeadlineNumber("gain_margin_db", "Gain margin", 8.1, "dB");
/// report.results()["gains"] = {{"k_p", 120.0}};
/// report.addSection("Bode plot").addLineChart({...});
/// report.write(out_dir);  // out_dir/summary.json, out_dir/report.html
/// @endcode
///
/// The summary.json schema is documented in docs/reports.md.

#include <chrono>
#include <deque>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

#include "fullarm/reports/section.hpp"

namespace fullarm::reports {

/// Value of the `schema_version` key of summary.json written by this library.
inline constexpr int kSummarySchemaVersion = 1;

/// File names of the two files every report folder holds.
inline constexpr std::string_view kSummaryFileName = "summary.json";
inline constexpr std::string_view kHtmlFileName = "report.html";

/// The fullarm version this library was built as, e.g. "0.1.0".
std::string_view fullarmVersion() noexcept;

/// The version of the plotly.js library inlined into every report.html, e.g. "4.1.2".
std::string_view plotlyVersion() noexcept;

/// The version of the three.js library inlined into a report.html that holds a 3D replay,
/// e.g. "0.180.0".
std::string_view threeVersion() noexcept;

/// The pass/fail outcome of a subcommand.
struct Verdict {
  bool pass = false;
  /// One sentence that says why, e.g. "Gain margin 8.1 dB >= 6 dB required".
  std::string headline{};
};

/// A key figure shown at the top of report.html and listed in summary.json.
struct HeadlineNumber {
  /// Stable machine-readable key, snake_case with the unit where it could be misread
  /// (`gain_margin_db`).
  std::string key{};
  /// Human-readable label ("Gain margin").
  std::string label{};
  /// The value, in `unit`. Non-finite values are written as JSON null and shown as "n/a".
  double value = 0.0;
  /// Unit symbol ("dB", "N·m"); empty if dimensionless.
  std::string unit{};
};

/// Everything a subcommand writes to its output folder. Build it up, then call write().
class Report {
 public:
  /// @param subcommand The subcommand that produced the report, e.g. "tune" or "arm show".
  /// @param title Human-readable title shown at the top of report.html.
  /// @throws std::invalid_argument if `subcommand` is empty.
  Report(std::string subcommand, std::string title);

  /// Sets the verdict (required before summary(), html() or write()).
  void setVerdict(bool pass, std::string headline);

  /// Appends a headline number.
  /// @throws std::invalid_argument if `key` is not snake_case ([a-z][a-z0-9_]*) or is already used.
  void addHeadlineNumber(std::string key, std::string label, double value, std::string unit);

  /// The subcommand's own machine-readable results: written as the `results` object of
  /// summary.json. Starts as an empty object; must still be an object when the report is
  /// written. NaN and infinities are written as null.
  nlohmann::json& results() noexcept { return results_; }
  /// @copydoc results()
  const nlohmann::json& results() const noexcept { return results_; }

  /// Appends a section and returns it. The reference stays valid for the Report's lifetime.
  Section& addSection(std::string heading);

  /// Lists a file the caller writes into the output folder itself (a CSV, an LCM log, ...)
  /// in summary.json `files` and links it from report.html.
  /// @param relative Path relative to the output folder, without "..".
  /// @throws std::invalid_argument if `relative` is empty, absolute, contains "..", or is
  ///   already listed (summary.json and report.html are always listed).
  void addFile(std::filesystem::path relative);

  /// Overrides the creation time (default: when the Report was constructed), e.g. for
  /// reproducible output.
  void setCreatedTime(std::chrono::system_clock::time_point created) noexcept;

  /// Builds summary.json (see docs/reports.md for the schema).
  /// @throws std::logic_error if no verdict is set or results() is not a JSON object.
  nlohmann::ordered_json summary() const;

  /// Builds the complete, self-contained report.html.
  /// @throws std::logic_error as summary().
  std::string html() const;

  /// Creates `out_dir` (and its parents) if needed and writes summary.json and report.html
  /// into it. Each file is written to a temporary file first and then renamed, so a reader
  /// never sees a half-written file.
  /// @return The paths of all listed files (out_dir / name): summary.json, report.html, then
  ///   those given to addFile(), in that order.
  /// @throws std::runtime_error naming the path and the operating-system error if the folder
  ///   cannot be created or a file cannot be written.
  /// @throws std::logic_error as summary().
  std::vector<std::filesystem::path> write(const std::filesystem::path& out_dir) const;

  const std::string& subcommand() const noexcept { return subcommand_; }
  const std::string& title() const noexcept { return title_; }
  /// The verdict, if set.
  const std::optional<Verdict>& verdict() const noexcept { return verdict_; }
  /// True if a verdict is set and it is a pass: use it for the subcommand's exit status.
  bool passed() const noexcept { return verdict_.has_value() && verdict_->pass; }
  const std::vector<HeadlineNumber>& headlineNumbers() const noexcept { return headline_numbers_; }
  const std::deque<Section>& sections() const noexcept { return sections_; }
  /// Names listed in summary.json `files`, relative to the output folder.
  std::vector<std::filesystem::path> files() const;
  std::chrono::system_clock::time_point createdTime() const noexcept { return created_; }

 private:
  void checkWritable() const;

  std::string subcommand_;
  std::string title_;
  std::optional<Verdict> verdict_;
  std::vector<HeadlineNumber> headline_numbers_;
  nlohmann::json results_ = nlohmann::json::object();
  std::deque<Section> sections_;
  std::vector<std::filesystem::path> extra_files_;
  std::chrono::system_clock::time_point created_;
};

}  // namespace fullarm::reports
