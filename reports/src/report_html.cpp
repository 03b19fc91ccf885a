// Report::html(): the report as one self-contained HTML page.
#include "fullarm/reports/report.hpp"

#include <cmath>
#include <string_view>
#include <type_traits>
#include <variant>

#include "assets.hpp"
#include "figures.hpp"
#include "replay3d_json.hpp"
#include "text.hpp"

namespace fullarm::reports::detail {
namespace {

using nlohmann::json;

constexpr int kHeadlineDigits = 4;

// The page may load nothing from anywhere: everything it needs is inline. A violation shows
// up as a console error (which the browser test treats as a failure).
constexpr std::string_view kContentSecurityPolicy =
    "default-src 'none'; script-src 'unsafe-inline'; style-src 'unsafe-inline'; "
    "img-src data: blob:; connect-src 'none'; font-src 'none'; base-uri 'none'; "
    "form-action 'none'";

// Builds the page body and collects the chart figures for the JSON data block.
class PageBuilder {
 public:
  explicit PageBuilder(std::string& out) : out_(out) {}

  void text(std::string_view escaped_or_markup) { out_ += escaped_or_markup; }
  void escaped(std::string_view caller_text) { out_ += escapeHtml(caller_text); }

  void block(const Paragraph& paragraph) {
    text("<p>");
    escaped(paragraph.text);
    text("</p>\n");
  }

  void block(const Table& table) {
    text("<div class=\"table-wrap\"><table>\n");
    if (!table.caption.empty()) {
      text("<caption>");
      escaped(table.caption);
      text("</caption>\n");
    }
    text("<thead><tr>");
    for (const std::string& column : table.columns) {
      text("<th scope=\"col\">");
      escaped(column);
      text("</th>");
    }
    text("</tr></thead>\n<tbody>\n");
    for (const std::vector<Cell>& row : table.rows) {
      text("<tr>");
      for (const Cell& cell : row) {
        std::visit(
            [&](const auto& value) {
              using T = std::decay_t<decltype(value)>;
              if constexpr (std::is_same_v<T, std::string>) {
                text("<td>");
                escaped(value);
              } else if constexpr (std::is_same_v<T, double>) {
                text("<td class=\"num\">");
                escaped(formatNumber(value, table.significant_digits));
              } else {
                text("<td class=\"num\">");
                text(std::to_string(value));
              }
            },
            cell.value());
        text("</td>");
      }
      text("</tr>\n");
    }
    text("</tbody></table></div>\n");
  }

  void block(const LineChart& chart) { figure(chart.chart.title, xyFigure(chart.chart, false), chart.chart.caption); }

  void block(const ScatterChart& chart) { figure(chart.chart.title, xyFigure(chart.chart, true), chart.chart.caption); }

  void block(const Histogram& histogram) {
    const HistogramBins bins = computeHistogramBins(histogram);
    std::string note = histogram.caption;
    const auto add_sentence = [&note](const Text& sentence) {
      if (!note.empty()) {
        note += note.back() == '.' ? " " : ". ";
      }
      note += sentence.str();
    };
    const std::size_t bin_count = bins.edges.size() - 1;
    if (histogram.x_axis.log) {
      add_sentence(Text() << bin_count << " bins, equally wide on the logarithmic axis.");
    } else {
      const double width = (bins.edges.back() - bins.edges.front()) / static_cast<double>(bin_count);
      Text sentence;
      sentence << bin_count << " bins of " << std::string_view(formatNumber(width, 3));
      if (!histogram.x_axis.unit.empty()) {
        sentence << ' ' << histogram.x_axis.unit;
      }
      add_sentence(sentence << '.');
    }
    for (std::size_t s = 0; s < histogram.series.size(); ++s) {
      const std::string& name = histogram.series[s].name;
      if (bins.missing[s] > 0) {
        add_sentence(Text() << bins.missing[s] << " missing (NaN) samples of \"" << name << "\" not counted.");
      }
      if (bins.out_of_range[s] > 0) {
        add_sentence(Text() << bins.out_of_range[s] << " samples of \"" << name << "\" outside the range not shown.");
      }
    }
    figure(histogram.title, histogramFigure(histogram, bins), note);
  }

  void block(const HeatMap& heat_map) { figure(heat_map.title, heatMapFigure(heat_map), heat_map.caption); }

  void block(const Replay3d& replay) {
    const std::string id = (Text() << "replay-" << replays_.size() + 1).str();
    text("<figure class=\"replay3d-figure\">\n<h3>");
    escaped(replay.title);
    text((Text() << "</h3>\n<div class=\"replay3d\" id=\"" << id << "\" data-replay3d=\"" << id
                 << "\" role=\"group\" aria-label=\"")
             .str());
    escaped(replay.title);
    text("\"></div>\n");
    if (!replay.caption.empty()) {
      text("<figcaption>");
      escaped(replay.caption);
      text("</figcaption>\n");
    }
    text("</figure>\n");
    replays_[id] = replayJson(replay);
  }

  json takeCharts() { return std::move(charts_); }
  json takeReplays() { return std::move(replays_); }

 private:
  void figure(const std::string& title, json plotly_figure, const std::string& caption) {
    const std::string id = (Text() << "chart-" << charts_.size() + 1).str();
    text("<figure class=\"chart-figure\">\n<h3>");
    escaped(title);
    text((Text() << "</h3>\n<div class=\"chart\" id=\"" << id << "\" data-chart=\"" << id
                 << "\" role=\"img\" aria-label=\"")
             .str());
    escaped(title);
    text("\"></div>\n");
    if (!caption.empty()) {
      text("<figcaption>");
      escaped(caption);
      text("</figcaption>\n");
    }
    text("</figure>\n");
    charts_[id] = std::move(plotly_figure);
  }

  std::string& out_;
  json charts_ = json::object();
  json replays_ = json::object();
};

// The caller has checked that the report has a verdict.
std::string renderHtml(const Report& report) {
  const Verdict& verdict = *report.verdict();
  const std::string_view plotly = plotlyJs();

  std::string body;
  PageBuilder page(body);

  // Header: title, verdict, headline numbers.
  page.text("<header class=\"report-header\">\n<p class=\"kicker\">fullarm ");
  page.escaped(report.subcommand());
  page.text("</p>\n<h1>");
  page.escaped(report.title());
  page.text("</h1>\n");
  page.text(verdict.pass ? "<div class=\"verdict pass\" role=\"status\"><span class=\"badge\">PASS</span>"
                         : "<div class=\"verdict fail\" role=\"status\"><span class=\"badge\">FAIL</span>");
  page.text("<span class=\"headline\">");
  page.escaped(verdict.headline);
  page.text("</span></div>\n");
  if (!report.headlineNumbers().empty()) {
    page.text("<dl class=\"numbers\">\n");
    for (const HeadlineNumber& number : report.headlineNumbers()) {
      page.text("<div class=\"number\" data-key=\"");
      page.escaped(number.key);
      page.text("\"><dt>");
      page.escaped(number.label);
      page.text("</dt><dd>");
      page.escaped(std::isfinite(number.value) ? formatNumber(number.value, kHeadlineDigits) : "n/a");
      if (!number.unit.empty()) {
        page.text("<span class=\"unit\">");
        page.escaped(number.unit);
        page.text("</span>");
      }
      page.text("</dd></div>\n");
    }
    page.text("</dl>\n");
  }
  page.text("</header>\n");

  // Contents, when there is more than one titled section.
  std::size_t titled_sections = 0;
  for (const Section& section : report.sections()) {
    titled_sections += section.heading().empty() ? 0 : 1;
  }
  if (titled_sections > 1) {
    page.text("<nav class=\"contents\" aria-label=\"Contents\"><strong>Contents</strong><ol>\n");
    std::size_t index = 0;
    for (const Section& section : report.sections()) {
      ++index;
      if (section.heading().empty()) {
        continue;
      }
      page.text((Text() << "<li><a href=\"#section-" << index << "\">").str());
      page.escaped(section.heading());
      page.text("</a></li>\n");
    }
    page.text("</ol></nav>\n");
  }

  // Sections.
  page.text("<main>\n");
  std::size_t index = 0;
  for (const Section& section : report.sections()) {
    page.text((Text() << "<section id=\"section-" << ++index << "\">\n").str());
    if (!section.heading().empty()) {
      page.text("<h2>");
      page.escaped(section.heading());
      page.text("</h2>\n");
    }
    if (section.columns() > 1) {
      page.text((Text() << "<div class=\"columns columns-" << section.columns() << "\">\n").str());
    }
    for (const Section::Block& block : section.blocks()) {
      if (section.columns() > 1) page.text("<div class=\"column-cell\">\n");
      std::visit([&page](const auto& content) { page.block(content); }, block);
      if (section.columns() > 1) page.text("</div>\n");
    }
    if (section.columns() > 1) page.text("</div>\n");
    page.text("</section>\n");
  }
  page.text("</main>\n");

  // Footer: files, provenance.
  page.text("<footer>\n<strong>Files in this folder</strong>\n<ul>\n");
  for (const std::filesystem::path& file : report.files()) {
    const std::string name = file.generic_string();
    page.text("<li><a href=\"");
    page.escaped(encodeUrlPath(name));
    page.text("\">");
    page.escaped(name);
    page.text("</a></li>\n");
  }
  page.text("</ul>\n<p>Generated by fullarm ");
  page.escaped(fullarmVersion());
  page.text(" <code>");
  page.escaped(report.subcommand());
  page.text("</code> on ");
  page.escaped(formatUtc(report.createdTime()));
  const json charts = page.takeCharts();
  const json replays = page.takeReplays();
  const bool has_replay = !replays.empty();
  page.text(". Charts drawn with plotly.js ");
  page.escaped(plotlyVersion());
  if (has_replay) {
    page.text(", the 3D replay with three.js ");
    page.escaped(threeVersion());
    page.text(" (both MIT licence), included");
  } else {
    page.text(" (MIT licence), included");
  }
  page.text(" in this file: it opens without a network.</p>\n</footer>\n");

  std::string html;
  html.reserve(body.size() + plotly.size() + 65536);
  html += "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n";
  html += "<meta http-equiv=\"Content-Security-Policy\" content=\"";
  html += kContentSecurityPolicy;
  html += "\">\n<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n";
  html += "<meta name=\"color-scheme\" content=\"light\">\n<meta name=\"generator\" content=\"fullarm ";
  html += escapeHtml(fullarmVersion());
  html += "\">\n<title>";
  html += escapeHtml(report.title());
  html += " · fullarm ";
  html += escapeHtml(report.subcommand());
  html += "</title>\n<style>\n";
  html += reportCss();
  html += "</style>\n</head>\n<body>\n";
  html += body;
  html += "<noscript><p>The charts need JavaScript; the tables and numbers above do not.</p></noscript>\n";
  html += "<script type=\"application/json\" id=\"fullarm-report-data\">";
  html += jsonForScript(json{{"charts", charts}, {"replays", replays}});
  html += "</script>\n<script>\n";
  html += plotly;
  html += "\n</script>\n<script>\n";
  if (has_replay) {
    html += replayJs();
    html += "\n</script>\n<script>\n";
  }
  html += reportJs();
  html += "</script>\n</body>\n</html>\n";
  return html;
}

}  // namespace
}  // namespace fullarm::reports::detail

namespace fullarm::reports {

std::string Report::html() const {
  checkWritable();
  return detail::renderHtml(*this);
}

}  // namespace fullarm::reports
