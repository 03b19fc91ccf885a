#include "fullarm/reports/report.hpp"

#include <cerrno>
#include <cstdio>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "text.hpp"

#ifndef FULLARM_VERSION
#error "FULLARM_VERSION must be defined (reports/CMakeLists.txt sets it from PROJECT_VERSION)"
#endif
#ifndef FULLARM_PLOTLY_VERSION
#error "FULLARM_PLOTLY_VERSION must be defined (reports/CMakeLists.txt reads it from node_modules)"
#endif

namespace fullarm::reports {
namespace {

namespace fs = std::filesystem;

bool isSnakeCase(std::string_view key) {
  if (key.empty() || key.front() < 'a' || key.front() > 'z') {
    return false;
  }
  for (const char c : key) {
    if (!((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_')) {
      return false;
    }
  }
  return true;
}

using detail::Text;

std::runtime_error writeError(const fs::path& path, int error_number) {
  return std::runtime_error(
      (Text() << "cannot write '" << path.string() << "': " << std::generic_category().message(error_number)).str());
}

// Writes `content` to `path` through a temporary file in the same folder and a rename.
void writeFileAtomically(const fs::path& path, std::string_view content) {
  fs::path temporary = path;
  temporary += ".tmp";
  std::FILE* file = std::fopen(temporary.c_str(), "wb");
  if (file == nullptr) {
    throw writeError(path, errno);
  }
  const std::size_t written = std::fwrite(content.data(), 1, content.size(), file);
  const int write_errno = errno;
  if (written != content.size()) {
    std::fclose(file);
    std::remove(temporary.c_str());
    throw writeError(path, write_errno);
  }
  if (std::fclose(file) != 0) {
    const int close_errno = errno;
    std::remove(temporary.c_str());
    throw writeError(path, close_errno);
  }
  std::error_code error;
  fs::rename(temporary, path, error);
  if (error) {
    std::remove(temporary.c_str());
    throw std::runtime_error((Text() << "cannot write '" << path.string() << "': " << error.message()).str());
  }
}

}  // namespace

std::string_view fullarmVersion() noexcept {
  return FULLARM_VERSION;
}

std::string_view threeVersion() noexcept {
  return FULLARM_THREE_VERSION;
}

std::string_view plotlyVersion() noexcept {
  return FULLARM_PLOTLY_VERSION;
}

Report::Report(std::string subcommand, std::string title)
    : subcommand_(std::move(subcommand)), title_(std::move(title)), created_(std::chrono::system_clock::now()) {
  if (subcommand_.empty()) {
    throw std::invalid_argument("Report: the subcommand name is empty");
  }
}

void Report::setVerdict(bool pass, std::string headline) {
  verdict_ = Verdict{pass, std::move(headline)};
}

void Report::addHeadlineNumber(std::string key, std::string label, double value, std::string unit) {
  if (!isSnakeCase(key)) {
    throw std::invalid_argument((Text() << "report \"" << title_ << "\": headline number key \"" << key
                                        << "\" is not snake_case (expected [a-z][a-z0-9_]*)")
                                    .str());
  }
  for (const HeadlineNumber& number : headline_numbers_) {
    if (number.key == key) {
      throw std::invalid_argument((Text() << "report \"" << title_ << "\": headline number key \"" << key
                                          << "\" is used twice (expected unique keys)")
                                      .str());
    }
  }
  headline_numbers_.push_back({std::move(key), std::move(label), value, std::move(unit)});
}

Section& Report::addSection(std::string heading) {
  return sections_.emplace_back(std::move(heading));
}

void Report::addFile(std::filesystem::path relative) {
  const std::string shown = relative.generic_string();
  if (relative.empty() || relative.is_absolute() || relative.has_root_path()) {
    throw std::invalid_argument((Text() << "report \"" << title_ << "\": file \"" << shown
                                        << "\" must be a non-empty path relative to the output folder")
                                    .str());
  }
  for (const fs::path& part : relative) {
    if (part == "..") {
      throw std::invalid_argument((Text() << "report \"" << title_ << "\": file \"" << shown
                                          << "\" must stay inside the output folder (no \"..\")")
                                      .str());
    }
  }
  relative = relative.lexically_normal();
  for (const fs::path& listed : files()) {
    if (listed == relative) {
      throw std::invalid_argument(
          (Text() << "report \"" << title_ << "\": file \"" << shown << "\" is already listed").str());
    }
  }
  extra_files_.push_back(std::move(relative));
}

void Report::setCreatedTime(std::chrono::system_clock::time_point created) noexcept {
  created_ = created;
}

std::vector<std::filesystem::path> Report::files() const {
  std::vector<fs::path> names{fs::path(kSummaryFileName), fs::path(kHtmlFileName)};
  names.insert(names.end(), extra_files_.begin(), extra_files_.end());
  return names;
}

void Report::checkWritable() const {
  if (!verdict_) {
    throw std::logic_error(
        (Text() << "report \"" << title_ << "\" (" << subcommand_ << "): setVerdict() was not called").str());
  }
  if (!results_.is_object()) {
    throw std::logic_error((Text() << "report \"" << title_ << "\" (" << subcommand_
                                   << "): results() must be a JSON object, not " << results_.type_name())
                               .str());
  }
}

nlohmann::ordered_json Report::summary() const {
  checkWritable();
  nlohmann::ordered_json numbers = nlohmann::ordered_json::array();
  for (const HeadlineNumber& number : headline_numbers_) {
    numbers.push_back({{"key", number.key}, {"label", number.label}, {"value", number.value}, {"unit", number.unit}});
  }
  nlohmann::ordered_json files_json = nlohmann::ordered_json::array();
  for (const fs::path& file : files()) {
    files_json.push_back(file.generic_string());
  }

  nlohmann::ordered_json summary;
  summary["schema_version"] = kSummarySchemaVersion;
  summary["fullarm_version"] = std::string(fullarmVersion());
  summary["subcommand"] = subcommand_;
  summary["title"] = title_;
  summary["created_utc"] = detail::formatUtc(created_);
  summary["verdict"] = {{"pass", verdict_->pass}, {"headline", verdict_->headline}};
  summary["headline_numbers"] = std::move(numbers);
  summary["results"] = nlohmann::ordered_json(results_);
  summary["files"] = std::move(files_json);
  return summary;
}

std::vector<std::filesystem::path> Report::write(const std::filesystem::path& out_dir) const {
  // Build everything first, so a logic error leaves no half-written folder behind.
  std::string summary_text = summary().dump(2, ' ', false, nlohmann::ordered_json::error_handler_t::replace);
  summary_text += '\n';
  const std::string html_text = html();

  std::error_code error;
  fs::create_directories(out_dir, error);
  if (error) {
    throw std::runtime_error(
        (Text() << "cannot create output folder '" << out_dir.string() << "': " << error.message()).str());
  }
  writeFileAtomically(out_dir / kSummaryFileName, summary_text);
  writeFileAtomically(out_dir / kHtmlFileName, html_text);

  std::vector<fs::path> paths;
  for (const fs::path& file : files()) {
    paths.push_back(out_dir / file);
  }
  return paths;
}

}  // namespace fullarm::reports
