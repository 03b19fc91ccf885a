#include "run_command.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "fullarm/core/config_error.hpp"
#include "fullarm/hil/lcm_transport.hpp"
#include "fullarm/hil/run.hpp"
#include "fullarm/hil/run_recording.hpp"
#include "fullarm/reports/report.hpp"
#include "output_files.hpp"
#include "run_replay3d.hpp"

namespace fullarm::app {
namespace {

constexpr std::size_t kMaxChartPoints = 2000;

std::string us(double seconds) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << seconds * 1e6 << " µs";
  return s.str();
}

reports::Series seriesOf(const std::string& name, const std::vector<hil::TickTelemetry>& t,
                         double (*value)(const hil::TickTelemetry&, int), int index) {
  reports::Series s;
  s.name = name;
  const std::size_t stride = std::max<std::size_t>(1, t.size() / kMaxChartPoints);
  for (std::size_t k = 0; k < t.size(); k += stride) {
    s.x.push_back(t[k].t_s);
    const double v = value(t[k], index);
    s.y.push_back(std::isfinite(v) ? v : std::nan(""));
  }
  return s;
}

nlohmann::json percentilesJson(const hil::Percentiles& p) {
  return {{"p50_s", p.p50_s}, {"p99_s", p.p99_s}, {"max_s", p.max_s}};
}

// Adds `replay` to `section`, or a note when it has nothing to draw (a model without capsule
// links, a log without a complete tick).
void addReplayOrNote(reports::Section& section, reports::Replay3d replay) {
  if (replay.links.empty() || replay.frames.empty()) {
    section.addParagraph(replay.title + ": nothing to draw (no capsule link or no complete tick).");
  } else {
    section.addReplay3d(std::move(replay));
  }
}

// The charts over time of the reports of `run` and `replay` (and of `run --mode both`, side by
// side). Each is empty (nullopt) when the run has nothing to show in it.

// The supervisor's events over time.
std::optional<reports::XyChart> eventsChart(const hil::RunResult& r) {
  if (r.events.empty()) return std::nullopt;
  reports::XyChart events;
  events.title = "Supervisor events";
  events.x_axis = {"Time", "s"};
  events.y_axis = {"Cause code (hover for its name)", ""};
  events.caption = "Each event at its time; the causes are listed in docs/hil.md, \"Safety\".";
  reports::Series info{"information", {}, {}, reports::SeriesMode::kMarkers, {}};
  reports::Series trips{"trip", {}, {}, reports::SeriesMode::kMarkers, {}};
  for (const hil::SupervisorEvent& e : r.events) {
    reports::Series& s = e.trip ? trips : info;
    s.x.push_back(e.t_s);
    s.y.push_back(static_cast<double>(e.cause));
    std::string label = hil::supervisorCauseName(e.cause);
    if (e.joint >= 0 && static_cast<std::size_t>(e.joint) < r.joint_names.size())
      label += " (" + r.joint_names[static_cast<std::size_t>(e.joint)] + ")";
    s.point_labels.push_back(std::move(label));
  }
  for (reports::Series* s : {&info, &trips}) {
    if (!s->x.empty()) events.series.push_back(std::move(*s));
  }
  return events;
}

std::optional<reports::XyChart> valveChart(const hil::RunResult& r) {
  if (r.telemetry.empty()) return std::nullopt;
  reports::XyChart valves;
  valves.title = "Valve commands";
  valves.x_axis = {"Time", "s"};
  valves.y_axis = {"Command", "V"};
  for (std::size_t k = 0; k < r.joint_names.size(); ++k) {
    valves.series.push_back(seriesOf(
        r.joint_names[k], r.telemetry,
        [](const hil::TickTelemetry& t, int j) { return t.valve_v[static_cast<std::size_t>(j)]; },
        static_cast<int>(k)));
  }
  return valves;
}

std::optional<reports::XyChart> torqueChart(const hil::RunResult& r, const hil::HilSession& session) {
  if (r.telemetry.empty()) return std::nullopt;
  reports::XyChart torques;
  torques.title = "Contact torques (Eq. 1-2, after the stale-minima fade)";
  torques.x_axis = {"Time", "s"};
  torques.y_axis = {"Torque", "N·m"};
  for (std::size_t k = 0; k < r.joint_names.size(); ++k) {
    torques.series.push_back(seriesOf(
        r.joint_names[k], r.telemetry,
        [](const hil::TickTelemetry& t, int j) { return t.tau_contact_nm[static_cast<std::size_t>(j)]; },
        session.tickModel().device_joints.modelIndex(static_cast<int>(k))));
  }
  return torques;
}

std::optional<reports::XyChart> linkForceChart(const hil::RunResult& r) {
  reports::XyChart link_forces;
  link_forces.title = "Contact force per link (rendered, before the fade)";
  link_forces.x_axis = {"Time", "s"};
  link_forces.y_axis = {"Force", "N"};
  for (std::size_t l = 0; l < r.link_names.size(); ++l) {
    reports::Series s = seriesOf(
        r.link_names[l], r.telemetry,
        [](const hil::TickTelemetry& t, int j) {
          const auto& f = t.link_force_W_n[static_cast<std::size_t>(j)];
          return std::sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        },
        static_cast<int>(l));
    if (std::any_of(s.y.begin(), s.y.end(), [](double v) { return std::isfinite(v) && v > 0.0; }))
      link_forces.series.push_back(std::move(s));
  }
  if (link_forces.series.empty()) return std::nullopt;
  return link_forces;
}

std::optional<reports::XyChart> distanceChart(const hil::RunResult& r) {
  reports::XyChart distance;
  distance.title = "Smallest tracked distance per link";
  distance.x_axis = {"Time", "s"};
  distance.y_axis = {"Distance", "m"};
  for (std::size_t l = 0; l < r.link_names.size(); ++l) {
    reports::Series s = seriesOf(
        r.link_names[l], r.telemetry,
        [](const hil::TickTelemetry& t, int j) {
          const double d = t.link_min_distance_m[static_cast<std::size_t>(j)];
          return std::isfinite(d) ? d : std::nan("");
        },
        static_cast<int>(l));
    if (std::any_of(s.y.begin(), s.y.end(), [](double v) { return std::isfinite(v); }))
      distance.series.push_back(std::move(s));
  }
  if (distance.series.empty()) return std::nullopt;
  return distance;
}

void addEventsChart(const hil::RunResult& r, reports::Section& section) {
  if (auto chart = eventsChart(r)) section.addScatterChart(std::move(*chart));
}

// Valve commands, contact torques, contact force per link, smallest tracked distance per link.
void addTelemetryCharts(const hil::RunResult& r, const hil::HilSession& session, reports::Section& forces) {
  for (std::optional<reports::XyChart> chart :
       {valveChart(r), torqueChart(r, session), linkForceChart(r), distanceChart(r)}) {
    if (chart) forces.addLineChart(std::move(*chart));
  }
}

void addRunReport(const hil::RunResult& r, const hil::HilSession& session, reports::Report& report) {
  const hil::RunTiming& tm = r.timing;
  const bool lockstep = r.options.clock == hil::ClockKind::kLockstep;
  report.addHeadlineNumber("ticks", "Ticks", static_cast<double>(tm.ticks), "");
  report.addHeadlineNumber("compute_p99_us", "Tick compute time p99", tm.compute.p99_s * 1e6, "µs");
  if (lockstep) {
    report.addHeadlineNumber("real_time_factor", "Faster than real time", tm.simulated_s / tm.wall_s, "×");
  } else {
    report.addHeadlineNumber("period_jitter_p99_us", "Period jitter p99", tm.period_jitter.p99_s * 1e6, "µs");
    report.addHeadlineNumber("overruns", "Overruns", static_cast<double>(tm.overruns), "");
  }
  report.addHeadlineNumber("supervisor_trips", "Supervisor trips", r.tripped ? 1.0 : 0.0, "");
  if (r.oracle_ran)
    report.addHeadlineNumber("missed_contact_ticks", "Missed-contact ticks",
                             static_cast<double>(r.missed_contact_ticks), "");
  if (!r.hand_W_m.empty())
    report.addHeadlineNumber("hand_to_target_m", "Hand to the path's end", r.hand_to_target_m, "m");

  nlohmann::json& results = report.results();
  results["run"] = {{"io", r.io_name},
                    {"clock", hil::clockKindName(r.options.clock)},
                    {"mode", r.options.mode == haptics::RenderMode::kFullArm ? "full-arm" : "hand-only"},
                    {"scene", r.options.scene.string()},
                    {"user", r.options.user.string()},
                    {"duration_s", r.options.duration_s},
                    {"seed", r.options.seed},
                    {"control_period_s", session.config().control_period_s},
                    {"global_period_ticks", session.config().global_period_ticks},
                    {"delivery_delay_ticks", session.config().delivery_delay_ticks}};
  results["timing"] = {{"ticks", tm.ticks},
                       {"simulated_s", tm.simulated_s},
                       {"wall_s", tm.wall_s},
                       {"compute", percentilesJson(tm.compute)},
                       {"period_jitter", percentilesJson(tm.period_jitter)},
                       {"overruns", tm.overruns},
                       {"max_consecutive_overruns", tm.max_consecutive_overruns},
                       {"plant_s", tm.plant_s},
                       {"tick_s", tm.tick_s},
                       {"search_s", tm.search_s},
                       {"oracle_s", tm.oracle_s},
                       {"searches", tm.searches},
                       {"realtime_scheduling", tm.realtime_scheduling},
                       {"realtime_notes", tm.realtime_notes}};
  nlohmann::json events = nlohmann::json::array();
  reports::Table event_table;
  event_table.caption = "Supervisor events (every trip latches the valves at null until a reset command)";
  event_table.columns = {"Tick", "Time [s]", "Kind", "Cause", "Joint", "Value"};
  for (const hil::SupervisorEvent& e : r.events) {
    const std::string joint = e.joint >= 0 && e.joint < static_cast<int>(r.joint_names.size())
                                  ? r.joint_names[static_cast<std::size_t>(e.joint)]
                                  : "";
    events.push_back({{"tick", e.tick},
                      {"t_s", e.t_s},
                      {"trip", e.trip},
                      {"cause", hil::supervisorCauseName(e.cause)},
                      {"joint", joint},
                      {"value", e.value}});
    if (event_table.rows.size() < 200) {
      event_table.rows.push_back({static_cast<double>(e.tick), e.t_s, e.trip ? "trip" : "info",
                                  hil::supervisorCauseName(e.cause), joint, e.value});
    }
  }
  results["supervisor"] = {
      {"tripped", r.tripped}, {"trip_cause", hil::supervisorCauseName(r.trip_cause)}, {"events", events}};
  nlohmann::json links = nlohmann::json::array();
  for (std::size_t l = 0; l < r.link_min_distance_m.size(); ++l) {
    links.push_back({{"link", r.link_names[l]},
                     {"min_distance_m", r.link_min_distance_m[l]},
                     {"max_penetration_m", r.link_max_penetration_m[l]},
                     {"penetration_s", r.link_penetration_s[l]}});
  }
  results["oracle"] = {{"ran", r.oracle_ran},
                       {"checked_ticks", r.oracle_ticks},
                       {"missed_contact_ticks", r.missed_contact_ticks},
                       {"sweep_exceeded_ticks", r.sweep_exceeded_ticks},
                       {"links", links}};
  results["user"] = {{"hand_to_target_m", r.hand_to_target_m}, {"max_force_n", r.max_user_force_n}};
  results["log"] = {{"file", "run.lcmlog"}, {"events", r.log_events}, {"records_dropped", r.log_records_dropped}};

  reports::Replay3d replay = runReplay3d(r, session);
  results["replay3d"] = replaySummary(replay, r);
  addReplayOrNote(report.addSection("3D replay"), std::move(replay));

  reports::Section& timing = report.addSection("Timing");
  reports::Table tt;
  tt.caption = lockstep ? "Lockstep run: simulated time, as fast as the machine allows"
                        : "Real-time run: the 1 kHz tick on an absolute-time clock";
  tt.columns = {"Quantity", "p50", "p99", "max"};
  tt.rows.push_back(
      {"Tick compute time (read, tick, write)", us(tm.compute.p50_s), us(tm.compute.p99_s), us(tm.compute.max_s)});
  if (!lockstep) {
    tt.rows.push_back({"Period jitter |wake-up - deadline|", us(tm.period_jitter.p50_s), us(tm.period_jitter.p99_s),
                       us(tm.period_jitter.max_s)});
  }
  timing.addTable(std::move(tt));
  if (!tm.compute_samples_s.empty()) {
    reports::Histogram loop;
    loop.title = lockstep ? "Loop timing: tick compute time" : "Loop timing: tick compute time and period jitter";
    loop.x_axis = {"Time", "µs"};
    const auto micro = [](const std::vector<double>& samples_s) {
      std::vector<double> out;
      out.reserve(samples_s.size());
      for (double s : samples_s) out.push_back(s * 1e6);
      return out;
    };
    loop.series.push_back({"Tick compute time", micro(tm.compute_samples_s)});
    double p99_us = tm.compute.p99_s * 1e6;
    if (!lockstep && !tm.period_jitter_samples_s.empty()) {
      loop.series.push_back({"Period jitter |wake-up - deadline|", micro(tm.period_jitter_samples_s)});
      p99_us = std::max(p99_us, tm.period_jitter.p99_s * 1e6);
    }
    // The rare long ticks would squeeze the bulk into one bin: the range ends at 4 x the larger
    // p99, and the note under the chart counts the samples beyond it.
    const double max_us = std::max(tm.compute.max_s, tm.period_jitter.max_s) * 1e6;
    if (std::isfinite(p99_us) && p99_us > 0.0 && max_us > 4.0 * p99_us)
      loop.range = std::array<double, 2>{0.0, 4.0 * p99_us};
    loop.caption = "Every tick of the run; the table above gives p50, p99 and max.";
    timing.addHistogram(std::move(loop));
  }
  std::ostringstream text;
  text << tm.ticks << " ticks, " << tm.simulated_s << " s of control time in " << tm.wall_s << " s of wall time; "
       << tm.overruns << " overruns (longest run " << tm.max_consecutive_overruns << "); " << tm.searches
       << " global searches.";
  if (lockstep) {
    text << " Wall time by part: plant " << tm.plant_s << " s, tick " << tm.tick_s << " s, global search "
         << tm.search_s << " s, missed-contact oracle " << tm.oracle_s << " s.";
  }
  for (const std::string& note : tm.realtime_notes) text << "\n" << note;
  timing.addParagraph(text.str());

  reports::Section& sup = report.addSection("Supervisor");
  sup.addParagraph(r.tripped ? std::string("Tripped: ") + hil::supervisorCauseName(r.trip_cause)
                             : "No trip: the run ended with the supervisor running.");
  if (!event_table.rows.empty()) sup.addTable(std::move(event_table));
  addEventsChart(r, sup);

  reports::Section& forces = report.addSection("Forces and torques");
  addTelemetryCharts(r, session, forces);
  if (r.oracle_ran) {
    reports::Table lt;
    lt.caption = "Each link against the scene (exact, every tick): the missed-contact oracle";
    lt.columns = {"Link", "Smallest distance [m]", "Deepest penetration [m]", "Time touching [s]"};
    for (std::size_t l = 0; l < r.link_min_distance_m.size(); ++l) {
      lt.rows.push_back(
          {r.link_names[l], r.link_min_distance_m[l], r.link_max_penetration_m[l], r.link_penetration_s[l]});
    }
    forces.addTable(std::move(lt));
  }
}

}  // namespace

void declareRunOptions(CLI::App& cmd, RunCommandOptions& o, OptionTable& table, RunFlavour flavour) {
  OptionDeclarer declare(cmd, table);
  declare.choice("--io", o.io, "I/O back-end", {"sim", "fakedaq", "comedi", "lcm"})->capture_default_str();
  if (flavour == RunFlavour::kRun) {
    declare
        .choice("--search", o.search, "Global search: in this process, or the global node `fullarm global` over LCM",
                {"in-process", "lcm"})
        ->capture_default_str();
  }
  declare.name("--lcm-url", o.lcm_url,
               std::string(flavour == RunFlavour::kRun ? "--io lcm, --search lcm: " : "") +
                   std::string("LCM URL of the plant and global nodes (default ") + hil::kDefaultLcmUrl + ")");
  if (flavour == RunFlavour::kRun) {
    declare
        .choice("--mode", o.mode,
                "Haptic rendering (both: the run in each mode, in full-arm/ and hand-only/, and a report of the two "
                "side by side)",
                {"full-arm", "hand-only", "both"})
        ->capture_default_str();
  } else {
    declare
        .choice("--mode", o.mode, "Haptic rendering (the global node's --mode must be the same)",
                {"full-arm", "hand-only"})
        ->capture_default_str();
  }
  declareLoopFiles(declare, o.files);
  // Every tick's inputs and telemetry stay in memory for the report and the replay check (the
  // LCM log holds them too): the duration is bounded before the run starts.
  declare.number("--duration", o.duration_s, "Run time (every tick is kept in memory: at most 600 s)",
                 {0.001, kMaxRunDuration_s, "s"});
  declare
      .choice("--clock", o.clock, "realtime: the 1 kHz wall clock; lockstep: simulated time, deterministic",
              {"realtime", "lockstep"})
      ->capture_default_str();
  declare.file("--user", o.user, "Scripted user YAML (default: config/user_reach_valve.yaml)");
  declare.folder("--out", o.out_dir, "Output folder")->capture_default_str();
  declare.integer("--seed", o.seed, "Seed of the simulated sensors' noise", 0, 2147483647);
  declare.name("--start-posture", o.start_posture, "Scene posture the simulated arm starts in")->capture_default_str();
  declare.file("--daq-config", o.daq_config, "Channel map YAML (default: config/dts_daq.yaml)");
  declare.integer("--delivery-delay-ticks", o.delivery_delay_ticks,
                  "Lockstep: ticks between a global query and the adoption of its result (default: the loop YAML's)", 1,
                  1000000);
  declare.flag("--no-oracle", o.no_oracle, "Lockstep: skip the missed-contact oracle");
}

CLI::App* addRunCommand(CLI::App& app, RunCommandOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand("run",
                                     "Run the 1 kHz haptic loop on a simulated, fake-DAQ or real DTS; write an "
                                     "LCM log, summary.json and report.html");
  declareRunOptions(*cmd, o, table, RunFlavour::kRun);
  return cmd;
}

namespace {

// The loop's options from the command's (the log goes into the output folder).
hil::RunOptions runOptionsOf(const RunCommandOptions& o, const std::string& command_line) {
  hil::RunOptions ro;
  ro.io = o.io == "sim"       ? hil::IoKind::kSim
          : o.io == "fakedaq" ? hil::IoKind::kFakeDaq
          : o.io == "lcm"     ? hil::IoKind::kLcm
                              : hil::IoKind::kComedi;
  ro.lcm_url = o.lcm_url;
  if (o.search == "lcm") ro.search_url = o.lcm_url.empty() ? hil::kDefaultLcmUrl : o.lcm_url;
  ro.mode = o.mode == "hand-only" ? haptics::RenderMode::kHandOnly : haptics::RenderMode::kFullArm;
  ro.clock = o.clock == "lockstep" ? hil::ClockKind::kLockstep : hil::ClockKind::kRealtime;
  ro.duration_s = o.duration_s;
  applyLoopFiles(o.files, ro);
  ro.user = pathOr(o.user);
  ro.daq_config = pathOr(o.daq_config);
  ro.seed = o.seed;
  ro.start_posture = o.start_posture;
  ro.oracle = !o.no_oracle && ro.clock == hil::ClockKind::kLockstep;
  if (o.delivery_delay_ticks) ro.delivery_delay_ticks = *o.delivery_delay_ticks;
  ro.log = std::filesystem::path(o.out_dir) / "run.lcmlog";
  ro.command_line = command_line;
  return ro;
}

// One of the two runs of `--mode both`, read back from its log.
struct ModeRun {
  std::string mode;
  int exit_code = 0;
  std::unique_ptr<hil::HilSession> session;
  hil::RunResult logged;
};

// A chart of one mode's run for the side-by-side sections, or a note in its place so that the
// two columns stay paired.
void addModeChart(reports::Section& section, const std::string& mode, std::optional<reports::XyChart> chart,
                  const std::string& what, bool scatter = false) {
  if (chart) {
    chart->title = mode + ": " + chart->title;
    if (scatter) {
      section.addScatterChart(std::move(*chart));
    } else {
      section.addLineChart(std::move(*chart));
    }
  } else {
    section.addParagraph(mode + ": no " + what + " in this run.");
  }
}

// `--mode both`: the same run in full-arm and then hand-only mode, each with its own output
// folder (full-arm/, hand-only/), and a report that shows the two side by side.
int runBothModes(const RunCommandOptions& o, const std::string& command_line) {
  const std::filesystem::path out = o.out_dir;
  std::vector<ModeRun> runs;
  for (const char* mode : {"full-arm", "hand-only"}) {
    RunCommandOptions one = o;
    one.mode = mode;
    one.out_dir = (out / mode).string();
    ModeRun run;
    run.mode = mode;
    run.exit_code = runRun(one, command_line);
    run.session = std::make_unique<hil::HilSession>(runOptionsOf(one, command_line), false);
    run.logged = runFromLog(out / mode / "run.lcmlog", *run.session);
    runs.push_back(std::move(run));
  }
  const bool pass = runs[0].exit_code == 0 && runs[1].exit_code == 0;
  reports::Report report("run", "Haptic run, full-arm and hand-only side by side: " + o.io + ", " + o.clock);
  report.setVerdict(pass, pass ? "Both runs ended without a trip or a missed contact"
                               : std::string("See the ") + (runs[0].exit_code != 0 ? "full-arm" : "hand-only") +
                                     " run's report: it did not pass");
  nlohmann::json modes = nlohmann::json::object();
  reports::Section& replays = report.addSection("3D replays: full-arm (left) and hand-only (right)").setColumns(2);
  for (ModeRun& run : runs) {
    reports::Replay3d replay = runReplay3d(run.logged, *run.session);
    replay.title = run.mode + ": " + replay.title;
    const nlohmann::json shown = replaySummary(replay, run.logged);
    std::uint64_t penetrating_ticks = 0;
    for (const hil::TickTelemetry& t : run.logged.telemetry) penetrating_ticks += t.link_penetration_mask != 0 ? 1 : 0;
    const double penetration_s = static_cast<double>(penetrating_ticks) * run.session->config().control_period_s;
    const std::string key = run.mode == "full-arm" ? "full_arm" : "hand_only";
    report.addHeadlineNumber(key + "_penetration_s", run.mode + ": time a link touched the scene", penetration_s, "s");
    modes[run.mode] = {
        {"folder", run.mode}, {"exit_code", run.exit_code}, {"penetration_s", penetration_s}, {"replay3d", shown}};
    addReplayOrNote(replays, std::move(replay));
    report.addFile(std::filesystem::path(run.mode) / "report.html");
  }
  report.results()["modes"] = modes;
  reports::Section& events = report.addSection("Supervisor events").setColumns(2);
  for (const ModeRun& run : runs) addModeChart(events, run.mode, eventsChart(run.logged), "supervisor event", true);
  reports::Section& torques = report.addSection("Contact torques").setColumns(2);
  for (const ModeRun& run : runs)
    addModeChart(torques, run.mode, torqueChart(run.logged, *run.session), "contact torque");
  reports::Section& forces = report.addSection("Contact force per link").setColumns(2);
  for (const ModeRun& run : runs) addModeChart(forces, run.mode, linkForceChart(run.logged), "contact force");
  reports::Section& distances = report.addSection("Smallest tracked distance per link").setColumns(2);
  for (const ModeRun& run : runs) addModeChart(distances, run.mode, distanceChart(run.logged), "tracked minimum");
  report.addSection("").addParagraph(
      "Each run's own report (timing, supervisor, valve commands, the oracle) is in its folder: full-arm/report.html "
      "and hand-only/report.html.");
  writeReport(report, o.out_dir);
  std::cout << "Report (side by side): " << (std::filesystem::absolute(out) / "report.html").string() << "\n";
  return pass ? 0 : 1;
}

}  // namespace

int runRun(const RunCommandOptions& o, const std::string& command_line, const std::string& command_name) {
  if (o.mode == "both") return runBothModes(o, command_line);
  const hil::RunOptions ro = runOptionsOf(o, command_line);
  std::filesystem::create_directories(o.out_dir);

  hil::HilSession session(ro);
  // The lines below set fixed notation on std::cout; each run's header starts from the default
  // (`--mode both` prints two runs).
  std::cout << std::defaultfloat << std::setprecision(6) << "fullarm " << command_name << ": " << o.io << ", " << o.mode
            << ", " << o.clock << " clock, " << o.duration_s << " s at " << 1.0 / session.config().control_period_s
            << " Hz, scene " << session.scene().name << "\n";
  const hil::RunResult r = session.run();
  const hil::RunTiming& tm = r.timing;
  for (const std::string& note : tm.realtime_notes) std::cout << "  " << note << "\n";
  std::cout << std::fixed << std::setprecision(1) << "  " << tm.ticks << " ticks in " << std::setprecision(3)
            << tm.wall_s << " s wall; tick compute p50 " << us(tm.compute.p50_s) << ", p99 " << us(tm.compute.p99_s)
            << ", max " << us(tm.compute.max_s) << "\n";
  if (ro.clock == hil::ClockKind::kRealtime) {
    std::cout << "  period jitter p50 " << us(tm.period_jitter.p50_s) << ", p99 " << us(tm.period_jitter.p99_s)
              << ", max " << us(tm.period_jitter.max_s) << "; " << tm.overruns << " overruns\n";
  } else {
    std::cout << "  " << std::setprecision(2) << tm.simulated_s / tm.wall_s << "x real time (plant " << tm.plant_s
              << " s, tick " << tm.tick_s << " s, global search " << tm.search_s << " s, oracle " << tm.oracle_s
              << " s)\n";
  }
  if (r.oracle_ran)
    std::cout << "  missed-contact ticks: " << r.missed_contact_ticks << " of " << r.oracle_ticks << "\n";
  if (!r.hand_W_m.empty())
    std::cout << std::setprecision(3) << "  hand to the path's end: " << r.hand_to_target_m << " m\n";
  std::cout << "  supervisor: "
            << (r.tripped ? std::string("TRIPPED (") + hil::supervisorCauseName(r.trip_cause) + ")" : "no trip")
            << "\n";

  const bool pass = !r.tripped && r.missed_contact_ticks == 0;
  reports::Report report("run", "Haptic run: " + std::string(hil::ioKindName(ro.io)) + ", " + o.mode + ", " + o.clock);
  report.setVerdict(pass, r.tripped ? std::string("The supervisor tripped: ") + hil::supervisorCauseName(r.trip_cause)
                          : r.missed_contact_ticks > 0 ? "The missed-contact oracle found contacts no minimum covered"
                                                       : "The run ended without a trip" +
                                                             std::string(r.oracle_ran ? " or a missed contact" : ""));
  report.addFile("run.lcmlog");
  addRunReport(r, session, report);
  writeReport(report, o.out_dir);
  std::cout << "  log: " << std::filesystem::absolute(ro.log).string()
            << "\nReport: " << (std::filesystem::absolute(o.out_dir) / "report.html").string() << "\n";
  return pass ? 0 : 1;
}

CLI::App* addReplayCommand(CLI::App& app, ReplayCommandOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand("replay",
                                     "Feed a run's LCM log through the same tick; check every force, torque and "
                                     "valve command bit for bit");
  cmd->add_option("log", o.log, "The run's LCM log (run.lcmlog)")->required()->check(CLI::ExistingFile);
  OptionDeclarer declare(*cmd, table);
  declare.folder("--out", o.out_dir, "Write summary.json and report.html to this folder");
  return cmd;
}

int runReplay(const ReplayCommandOptions& o) {
  const hil::ReplayReport r = hil::replayLog(o.log);
  if (r.truncated) std::cerr << "fullarm: warning: " << r.warning << "\n";
  for (const std::string& f : r.changed_files) {
    std::cerr << "fullarm: warning: input file changed since the run: " << f << "\n";
  }
  const bool pass = r.identical();
  std::cout << "fullarm replay: " << r.ticks << " ticks, " << r.sets << " minima sets (" << r.clock << " run)\n"
            << "  valve commands: " << r.valve_mismatches << " ticks differ; contact torques: " << r.torque_mismatches
            << "; link forces: " << r.force_mismatches << "\n"
            << (pass ? "  reproduced bit for bit\n" : "  NOT reproduced: " + r.first_mismatch + "\n");
  if (!r.io_node.empty()) {
    std::cout << "  recorded over LCM on a node that said it serves:\n";
    for (const auto& [key, value] : r.io_node)
      std::cout << "    " << key << ": " << (value.empty() ? "(none)" : value) << "\n";
  }
  if (!o.out_dir.empty()) {
    reports::Report report("replay", "Replay of " + std::filesystem::path(o.log).filename().string());
    report.setVerdict(pass, pass ? "Every force, torque and valve command reproduced bit for bit"
                                 : "Not reproduced: " + r.first_mismatch);
    report.addHeadlineNumber("ticks", "Ticks replayed", static_cast<double>(r.ticks), "");
    report.addHeadlineNumber("valve_mismatches", "Ticks with a different valve command",
                             static_cast<double>(r.valve_mismatches), "");
    report.results()["replay"] = {{"log", std::filesystem::absolute(o.log).string()},
                                  {"clock", r.clock},
                                  {"ticks", r.ticks},
                                  {"sets", r.sets},
                                  {"valve_mismatches", r.valve_mismatches},
                                  {"torque_mismatches", r.torque_mismatches},
                                  {"force_mismatches", r.force_mismatches},
                                  {"truncated", r.truncated},
                                  {"warning", r.warning},
                                  {"changed_files", r.changed_files},
                                  {"io_node", nlohmann::json::object()}};
    for (const auto& [key, value] : r.io_node) report.results()["replay"]["io_node"][key] = value;
    // What the log shows of the run: its 3D replay and its charts over time.
    const hil::HilSession session(r.options, false);
    const hil::RunResult logged = runFromLog(o.log, session);
    if (!logged.telemetry.empty()) {
      reports::Replay3d replay = runReplay3d(logged, session);
      report.results()["replay3d"] = replaySummary(replay, logged);
      addReplayOrNote(report.addSection("3D replay"), std::move(replay));
      reports::Section& charts = report.addSection("Supervisor, forces and torques (as logged)");
      addEventsChart(logged, charts);
      addTelemetryCharts(logged, session, charts);
    }
    writeReport(report, o.out_dir);
  }
  return pass ? 0 : 1;
}

}  // namespace fullarm::app
