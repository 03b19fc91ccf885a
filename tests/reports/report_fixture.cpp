// Writes a report with every content kind, for the browser test (check_report.mjs).
// Usage: report_fixture <output folder>

#include <cmath>
#include <cstdio>
#include <exception>
#include <fstream>
#include <numbers>
#include <random>

#include "fullarm/reports/report.hpp"

namespace {

using namespace fullarm::reports;

// Second-order joint response magnitude |G(j 2 pi f)| for the line chart.
double magnitude(double frequency_hz, double natural_hz, double damping) {
  const double r = frequency_hz / natural_hz;
  return 1.0 / std::sqrt((1.0 - r * r) * (1.0 - r * r) + (2.0 * damping * r) * (2.0 * damping * r));
}

Report makeReport() {
  Report report("report-fixture", "Report fixture: every chart kind <and> escaping & \"quotes\"");
  report.setVerdict(true, "All chart kinds rendered from a self-contained file");
  report.addHeadlineNumber("gain_margin_db", "Gain margin", 8.13, "dB");
  report.addHeadlineNumber("phase_margin_deg", "Phase margin", 52.4, "°");
  report.addHeadlineNumber("loop_period_p99_ms", "Loop period, 99th percentile", 1.0213, "ms");
  report.addHeadlineNumber("trials", "Trials", 12, "");
  report.results()["fixture"] = true;

  Section& response = report.addSection("Frequency response");
  response.addParagraph(
      "Closed-loop magnitude of three joints. The y axis is logarithmic.\n"
      "A second line of prose, kept as written.");
  XyChart bode;
  bode.title = "Closed-loop magnitude";
  bode.x_axis = {"Frequency", "Hz", true};
  bode.y_axis = {"Magnitude", "", true};
  bode.caption = "Log–log axes; the resonance moves with damping.";
  const double dampings[] = {0.1, 0.3, 0.7};
  for (int joint = 0; joint < 3; ++joint) {
    Series series;
    series.name = "Joint " + std::to_string(joint + 1) + " (ζ = " + std::to_string(dampings[joint]).substr(0, 3) + ")";
    for (int i = 0; i <= 200; ++i) {
      const double f = std::pow(10.0, -1.0 + 3.0 * i / 200.0);
      series.x.push_back(f);
      series.y.push_back(magnitude(f, 5.0 + 3.0 * joint, dampings[joint]));
    }
    bode.series.push_back(std::move(series));
  }
  response.addLineChart(bode);

  Section& study = report.addSection("Valve study");
  XyChart scatter;
  scatter.title = "Reach against peak push force";
  scatter.x_axis = {"Reach distance", "m", false};
  scatter.y_axis = {"Peak push force", "N", false};
  std::mt19937 random(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  for (const char* mode : {"full arm", "hand & forearm"}) {
    Series series;
    series.name = mode;
    for (int trial = 0; trial < 12; ++trial) {
      const double reach = 0.45 + 0.03 * trial;
      series.x.push_back(reach);
      series.y.push_back((mode[0] == 'f' ? 180.0 : 120.0) - 90.0 * reach + 6.0 * noise(random));
      series.point_labels.push_back(std::string(mode) + " trial " + std::to_string(trial + 1));
    }
    scatter.series.push_back(std::move(series));
  }
  study.addScatterChart(scatter);

  Table table;
  table.caption = "Trials per valve";
  table.columns = {"Valve", "Trials", "Reached", "Median force [N]"};
  table.rows = {{"Ball valve <DN50>", 4, 4, 132.25},
                {"Wheel valve", 4, 3, 97.5},
                {"Lever behind truss", 4, 1, std::numeric_limits<double>::quiet_NaN()}};
  study.addTable(table);

  HeatMap heat_map;
  heat_map.title = "Force margin over the opening";
  heat_map.x_axis = {"Opening x", "m", false};
  heat_map.y_axis = {"Opening z", "m", false};
  heat_map.z_axis = {"Force margin", "N", false};
  heat_map.color_scale = ColorScale::kDiverging;
  for (int i = 0; i < 40; ++i) {
    heat_map.x.push_back(-0.2 + 0.01 * i);
  }
  for (int j = 0; j < 30; ++j) {
    heat_map.y.push_back(0.8 + 0.01 * j);
  }
  for (int j = 0; j < 30; ++j) {
    std::vector<double> row;
    for (int i = 0; i < 40; ++i) {
      const double x = heat_map.x[static_cast<std::size_t>(i)];
      const double z = heat_map.y[static_cast<std::size_t>(j)] - 0.95;
      // Unreachable corner: no value.
      row.push_back(x > 0.15 && z > 0.1 ? std::numeric_limits<double>::quiet_NaN() : 40.0 - 900.0 * (x * x + z * z));
    }
    heat_map.z.push_back(std::move(row));
  }
  heat_map.caption = "Blank cells: the technician's hand cannot reach them.";
  study.addHeatMap(heat_map);

  Section& timing = report.addSection("Real-time loop");
  Histogram histogram;
  histogram.title = "Loop period";
  histogram.x_axis = {"Period", "ms", false};
  histogram.series.push_back({"local node", {}});
  histogram.series.push_back({"global search (period < 2 ms)", {}});
  std::normal_distribution<double> period(1.0, 0.008);
  std::normal_distribution<double> search_period(1.02, 0.02);
  for (int i = 0; i < 20000; ++i) {
    histogram.series[0].samples.push_back(period(random));
  }
  for (int i = 0; i < 5000; ++i) {
    histogram.series[1].samples.push_back(search_period(random));
  }
  timing.addHistogram(histogram);

  Histogram jitter;
  jitter.title = "Wake-up latency (log bins)";
  jitter.x_axis = {"Latency", "µs", true};
  jitter.series.push_back({"latency", {}});
  std::lognormal_distribution<double> latency(std::log(12.0), 0.6);
  for (int i = 0; i < 10000; ++i) {
    jitter.series[0].samples.push_back(latency(random));
  }
  timing.addHistogram(jitter);

  // A 3D replay: a two-link arm swinging its forearm through a wall over 2 s (25 frames/s).
  Replay3d replay;
  replay.title = "Two-link arm through a wall";
  replay.meshes.push_back(
      {"wall", {{0.3, -0.5, -0.8}, {0.3, 0.5, -0.8}, {0.3, 0.5, 0.4}, {0.3, -0.5, 0.4}}, {{0, 1, 2}, {0, 2, 3}}});
  replay.links = {{"upper arm", 0.05}, {"forearm", 0.04}};
  replay.joints = {"shoulder", "elbow"};
  replay.torque_scale_nm = 5.0;
  replay.force_scale_n = 20.0;
  for (int f = 0; f <= 50; ++f) {
    const double t = 0.04 * f;
    const double angle = -0.3 + 0.9 * t;  // forearm angle from straight down [rad]
    const double ex = 0.0;
    const double ez = -0.3;
    const double hx = ex + 0.35 * std::sin(angle);
    const double hz = ez - 0.35 * std::cos(angle);
    ReplayFrame frame;
    frame.t_s = t;
    frame.segments_m = {{0.0, 0.0, 0.0, ex, 0.0, ez}, {ex, 0.0, ez, hx, 0.0, hz}};
    const bool through = hx + 0.04 >= 0.3;
    frame.penetrating = {false, through};
    frame.torques_nm = {2.0 * std::sin(3.0 * t), through ? -4.0 : 0.5};
    if (hx > 0.1) frame.minima.push_back({{hx, 0.0, hz}, {0.3, 0.0, hz}, through ? 20.0 : 20.0 * (hx - 0.1) / 0.16});
    replay.frames.push_back(std::move(frame));
  }
  replay.events = {{0.2, "start-up guard released", false}, {1.9, "trip: contact torque limit", true}};
  replay.caption = "Synthetic: the forearm passes through the wall and is drawn red while it does.";
  report.addSection("3D replay").addReplay3d(std::move(replay));

  report.addFile("trials.csv");
  return report;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: %s <output folder>\n", argv[0]);
    return 2;
  }
  try {
    const Report report = makeReport();
    const std::filesystem::path out_dir = argv[1];
    std::filesystem::create_directories(out_dir);
    std::ofstream(out_dir / "trials.csv") << "trial,reach_m,peak_force_n\n1,0.45,140.2\n";
    for (const auto& path : report.write(out_dir)) {
      std::printf("%s\n", path.c_str());
    }
    return 0;
  } catch (const std::exception& error) {
    std::fprintf(stderr, "report_fixture: %s\n", error.what());
    return 1;
  }
}
