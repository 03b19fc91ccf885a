#include "validate_command.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <iomanip>
#include <iostream>
#include <numbers>
#include <sstream>
#include <vector>

#include "cli_values.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/design/validate_arm.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "output_files.hpp"

namespace fullarm::app {
namespace {

// Largest number of frequency points per Bode/Nyquist series in the report.
constexpr std::size_t kMaxFrequencyPoints = 300;

std::string fixed(double v, int digits) {
  std::ostringstream os;
  os << std::setprecision(digits) << v;
  return os.str();
}

// Thins a frequency response to at most kMaxFrequencyPoints points.
std::vector<std::size_t> thinned(std::size_t n) {
  std::vector<std::size_t> idx;
  const std::size_t step = std::max<std::size_t>(1, n / kMaxFrequencyPoints);
  for (std::size_t i = 0; i < n; i += step) idx.push_back(i);
  return idx;
}

nlohmann::json toJson(const design::ArmValidationResult& out) {
  nlohmann::json joints = nlohmann::json::array();
  for (const design::JointValidationResult& o : out.joints) {
    const design::LinearChecks& f = o.linear.free;
    const design::LinearChecks& c = o.linear.contact;
    nlohmann::json zw = nlohmann::json::array();
    for (const design::ZWidthPoint& p : o.linear.z_width) {
      zw.push_back({{"wall_damping_nms_per_rad", p.damping_nms_per_rad},
                    {"max_wall_stiffness_nm_per_rad", p.max_stiffness_nm_per_rad}});
    }
    const design::MonteCarloRun& worst = o.monte_carlo.runs[static_cast<std::size_t>(o.monte_carlo.worst)];
    nlohmann::json j = {
        {"name", o.nominal.joint_name},
        {"pass", o.pass},
        {"verdict", o.verdict},
        {"linear",
         {{"pass", o.linear.pass},
          {"reason", o.linear.reason},
          {"free",
           {{"spectral_radius", f.spectral_radius},
            {"gain_margin", f.margins.gain_margin},
            {"phase_margin_deg", f.margins.phase_margin_deg},
            {"delay_margin_s", f.margins.delay_margin_s},
            {"peak_sensitivity", f.margins.peak_sensitivity},
            {"min_real_loop", f.margins.min_real},
            {"sector_ok", f.sector_ok},
            {"min_real_impedance_nms_per_rad", f.min_real_impedance},
            {"passive", f.passive},
            {"gain_scale_upper", f.gain_scale_upper}}},
          {"contact",
           {{"spectral_radius", c.spectral_radius},
            {"gain_margin", c.margins.gain_margin},
            {"phase_margin_deg", c.margins.phase_margin_deg},
            {"peak_sensitivity", c.margins.peak_sensitivity},
            {"min_real_loop", c.margins.min_real},
            {"sector_ok", c.sector_ok},
            {"min_real_impedance_nms_per_rad", c.min_real_impedance},
            {"passive", c.passive},
            {"gain_scale_upper", c.gain_scale_upper}}},
          {"delays", o.linear.delays},
          {"free_spectral_radius", o.linear.free_spectral_radius},
          {"contact_spectral_radius", o.linear.contact_spectral_radius},
          {"predicted_gain_limit", o.linear.predicted_gain_limit},
          {"z_width", zw}}},
        {"monte_carlo",
         {{"samples", o.monte_carlo.runs.size()},
          {"failures", o.monte_carlo.failures},
          {"too_sluggish", o.monte_carlo.sluggish},
          {"wall_not_reached", o.monte_carlo.wall_not_reached},
          {"worst",
           {{"index", worst.sample.index},
            {"severity", worst.severity},
            {"stable", worst.result.stable},
            {"failure", worst.result.failure},
            {"bulk_modulus_scale", worst.sample.bulk_modulus_scale},
            {"valve_gain_scale", worst.sample.valve_gain_scale},
            {"friction_scale", worst.sample.friction_scale},
            {"inertia_scale", worst.sample.inertia_scale},
            {"user_stiffness_nm_per_rad", worst.sample.user_stiffness_nm_per_rad},
            {"user_damping_nms_per_rad", worst.sample.user_damping_nms_per_rad},
            {"delay_samples", worst.sample.delay_samples}}}}},
    };
    if (o.has_claim) {
      const auto fig = [](const design::ControllerFigures& x) {
        return nlohmann::json{{"free_rms_user_torque_nm", x.free_rms_user_torque_nm},
                              {"free_peak_user_torque_nm", x.free_peak_user_torque_nm},
                              {"onset_peak_valve_v", x.onset_peak_valve_v},
                              {"max_stable_wall_nm_per_rad", x.max_stable_wall_nm_per_rad}};
      };
      j["paper_claim"] = {{"matched_transparency", o.claim.matched},    {"pid_gain_scale", o.claim.pid_gain_scale},
                          {"pid_kp_v_per_nm", o.claim.pid_kp_v_per_nm}, {"admittance", fig(o.claim.admittance)},
                          {"torque_pid", fig(o.claim.torque_pid)},      {"simulations", o.claim.simulations}};
    }
    joints.push_back(std::move(j));
  }
  return {{"pass", out.pass()},
          {"gains", out.gains_source.string()},
          {"ranges", out.config.source.string()},
          {"samples_per_joint", out.config.samples},
          {"seed", out.config.seed},
          {"threads", out.threads},
          {"wall_time_s", out.wall_s},
          {"monte_carlo_wall_time_s", out.monte_carlo_wall_s},
          {"joints", joints}};
}

void addToReport(const design::ArmValidationResult& out, reports::Report& report, const std::string& prefix) {
  int passed = 0, runs = 0, failures = 0;
  for (const design::JointValidationResult& o : out.joints) {
    passed += o.pass ? 1 : 0;
    runs += static_cast<int>(o.monte_carlo.runs.size());
    failures += o.monte_carlo.failures;
  }
  report.addHeadlineNumber(prefix + "joints_passed", "Joints passed", passed, "");
  report.addHeadlineNumber(prefix + "monte_carlo_runs", "Monte-Carlo runs", runs, "");
  report.addHeadlineNumber(prefix + "monte_carlo_failures", "Monte-Carlo failures", failures, "");
  report.addHeadlineNumber(prefix + "validate_wall_time_s", "Validation wall time", out.wall_s, "s");

  reports::Section& verdict = report.addSection("Validation verdict per joint");
  verdict.addParagraph(
      "Each joint passes when its linear checks pass (discrete closed loop stable, free and against the wall, for "
      "every computation delay of the Monte-Carlo range; plus any gated margin) and every Monte-Carlo run is stable "
      "and not too sluggish (a push above twice the breakaway friction must reach the wall): "
      "the nonlinear CVODES plant with the controller at " +
      fixed(1.0 / out.joints.front().nominal.dt_s, 4) + " Hz, " + std::to_string(out.config.samples) +
      " runs per joint, seed " + std::to_string(out.config.seed) +
      ", free motion driven by the user then contact with a " + fixed(out.config.wall.stiffness_nm_per_rad, 4) +
      " N m/rad wall. Gains: " + out.gains_source.string() + ".");
  reports::Table t;
  t.caption = "Verdicts";
  t.columns = {
      "Joint",     "Verdict",  "Spectral radius (free)", "Spectral radius (wall)", "GM",          "PM [deg]",
      "Ms",        "min Re L", "min Re Z [N m s/rad]",   "Gain limit (x)",         "MC failures", "Wall not reached",
      "Worst case"};
  t.significant_digits = 4;
  for (const design::JointValidationResult& o : out.joints) {
    const design::MonteCarloRun& worst = o.monte_carlo.runs[static_cast<std::size_t>(o.monte_carlo.worst)];
    const double ms = std::max(o.linear.free.margins.peak_sensitivity, o.linear.contact.margins.peak_sensitivity);
    t.rows.push_back({shortJointName(o.nominal.joint_name), o.pass ? std::string("PASS") : "FAIL: " + o.verdict,
                      o.linear.free.spectral_radius, o.linear.contact.spectral_radius,
                      o.linear.free.margins.gain_margin, o.linear.free.margins.phase_margin_deg, ms,
                      std::min(o.linear.free.margins.min_real, o.linear.contact.margins.min_real),
                      std::min(o.linear.free.min_real_impedance, o.linear.contact.min_real_impedance),
                      o.linear.predicted_gain_limit,
                      std::to_string(o.monte_carlo.failures) + " / " + std::to_string(o.monte_carlo.runs.size()),
                      std::to_string(o.monte_carlo.wall_not_reached),
                      "#" + std::to_string(worst.sample.index) + ": " + design::describeVariation(worst.sample) +
                          (worst.result.acceptable() ? " (stable)" : " -> " + worst.result.failure)});
  }
  verdict.addTable(std::move(t));

  // Bode and Nyquist of the loop at the valve command (free motion).
  reports::Section& freq = report.addSection("Loop at the valve command (linear, free motion)");
  freq.addParagraph(
      "L is the discrete loop transfer broken at the valve command (negative-feedback convention, ZOH, computation "
      "delay and sensor filter included), at the end of the free move with the user's arm coupled. Nyquist: the loop "
      "must not encircle -1; the circle criterion for sat() asks Re L > -1.");
  reports::XyChart mag{"Bode magnitude |L|", {"Frequency", "Hz", true}, {"|L|", "dB", false}, {}, ""};
  reports::XyChart phase{"Bode phase of L", {"Frequency", "Hz", true}, {"Phase", "deg", false}, {}, ""};
  reports::XyChart nyq{"Nyquist plot of L", {"Re L", "", false}, {"Im L", "", false}, {}, ""};
  reports::XyChart imp{
      "Rendered impedance |Z| (free motion)", {"Frequency", "Hz", true}, {"|Z|", "N m s/rad", true}, {}, ""};
  for (const design::JointValidationResult& o : out.joints) {
    const design::FrequencyData& fd = o.linear.free.frequency;
    reports::Series m{shortJointName(o.nominal.joint_name), {}, {}, reports::SeriesMode::kAuto, {}};
    reports::Series p = m, n = m, z = m;
    n.mode = reports::SeriesMode::kLines;
    double unwrap = 0.0, prev = 0.0;
    for (std::size_t i : thinned(fd.frequency_hz.size())) {
      const std::complex<double> L = fd.loop[i];
      m.x.push_back(fd.frequency_hz[i]);
      m.y.push_back(20.0 * std::log10(std::max(std::abs(L), 1e-12)));
      double ph = std::arg(L) * 180.0 / std::numbers::pi + unwrap;
      if (!p.y.empty() && ph - prev > 180.0) {
        unwrap -= 360.0;
        ph -= 360.0;
      }
      if (!p.y.empty() && ph - prev < -180.0) {
        unwrap += 360.0;
        ph += 360.0;
      }
      prev = ph;
      p.x.push_back(fd.frequency_hz[i]);
      p.y.push_back(ph);
      // Nyquist clipped to a readable window around -1.
      n.x.push_back(std::clamp(L.real(), -5.0, 5.0));
      n.y.push_back(std::clamp(L.imag(), -5.0, 5.0));
      const double zabs = std::abs(fd.impedance[i]);
      if (zabs > 0.0 && std::isfinite(zabs)) {
        z.x.push_back(fd.frequency_hz[i]);
        z.y.push_back(zabs);
      }
    }
    mag.series.push_back(std::move(m));
    phase.series.push_back(std::move(p));
    nyq.series.push_back(std::move(n));
    if (!z.x.empty()) imp.series.push_back(std::move(z));
  }
  nyq.series.push_back({"-1", {-1.0}, {0.0}, reports::SeriesMode::kMarkers, {"critical point"}});
  nyq.caption = "Axes clipped to [-5, 5].";
  freq.addLineChart(std::move(mag));
  freq.addLineChart(std::move(phase));
  freq.addLineChart(std::move(nyq));
  if (!imp.series.empty()) freq.addLineChart(std::move(imp));

  // Z-width.
  reports::Section& zw = report.addSection("Z-width (linear)");
  zw.addParagraph(
      "Largest virtual-wall stiffness for which the linear closed loop (joint, user, wall, controller, delay) is "
      "stable, against the wall's damping.");
  reports::XyChart zc{
      "Z-width", {"Wall damping", "N m s/rad", false}, {"Largest stable wall stiffness", "N m/rad", true}, {}, ""};
  for (const design::JointValidationResult& o : out.joints) {
    reports::Series s{shortJointName(o.nominal.joint_name), {}, {}, reports::SeriesMode::kLinesMarkers, {}};
    for (const design::ZWidthPoint& p : o.linear.z_width) {
      if (p.max_stiffness_nm_per_rad <= 0.0) continue;
      s.x.push_back(p.damping_nms_per_rad);
      s.y.push_back(p.max_stiffness_nm_per_rad);
    }
    if (!s.x.empty()) zc.series.push_back(std::move(s));
  }
  if (!zc.series.empty()) zw.addLineChart(std::move(zc));

  // Monte-Carlo histograms.
  reports::Section& mc = report.addSection("Monte-Carlo (nonlinear simulations)");
  mc.addParagraph("Samples drawn uniformly from " + out.config.source.string() +
                  ": oil bulk modulus, valve flow gain, friction, inertia, user stiffness and damping, 1-3 samples of "
                  "computation delay. Each run: free motion then a virtual wall; the detector flags sustained speed "
                  "oscillation in either hold and wall chatter. Monte-Carlo wall time " +
                  fixed(out.monte_carlo_wall_s, 3) + " s on " + std::to_string(out.threads) + " threads.");
  reports::Histogram h1{"RMS user torque in free motion", {"RMS user torque", "N·m", false}, {}, 0, std::nullopt, ""};
  reports::Histogram h2{
      "Hold speed deviation over the detector threshold", {"Deviation / threshold", "", false}, {}, 0, std::nullopt,
      "Above 1 (and sustained) is an oscillation."};
  reports::Histogram h3{
      "Rendered wall stiffness", {"User torque / penetration", "N m/rad", false}, {}, 0, std::nullopt, ""};
  for (const design::JointValidationResult& o : out.joints) {
    reports::HistogramSeries a{shortJointName(o.nominal.joint_name), {}}, b = a, c = a;
    for (const design::MonteCarloRun& r : o.monte_carlo.runs) {
      a.samples.push_back(r.result.free_rms_user_torque_nm);
      b.samples.push_back(std::max(r.result.free_hold_speed_rms_radps, r.result.contact_hold_speed_rms_radps) /
                          out.config.oscillation_speed_radps);
      c.samples.push_back(r.result.contact_rendered_stiffness_nm_per_rad > 0.0
                              ? r.result.contact_rendered_stiffness_nm_per_rad
                              : std::nan(""));
    }
    h1.series.push_back(std::move(a));
    h2.series.push_back(std::move(b));
    h3.series.push_back(std::move(c));
  }
  mc.addHistogram(std::move(h1));
  mc.addHistogram(std::move(h2));
  mc.addHistogram(std::move(h3));

  // The worst run of the worst joint.
  const auto worst_joint =
      std::max_element(out.joints.begin(), out.joints.end(),
                       [](const design::JointValidationResult& a, const design::JointValidationResult& b) {
                         return a.monte_carlo.runs[static_cast<std::size_t>(a.monte_carlo.worst)].severity <
                                b.monte_carlo.runs[static_cast<std::size_t>(b.monte_carlo.worst)].severity;
                       });
  if (worst_joint != out.joints.end() && !worst_joint->worst_trace.t_s.empty()) {
    const design::ClosedLoopTrace& tr = worst_joint->worst_trace;
    const design::MonteCarloRun& w =
        worst_joint->monte_carlo.runs[static_cast<std::size_t>(worst_joint->monte_carlo.worst)];
    reports::Section& ws = report.addSection("Worst case found: " + shortJointName(worst_joint->nominal.joint_name) +
                                             " run #" + std::to_string(w.sample.index));
    ws.addParagraph(
        design::describeVariation(w.sample) + ". " +
        (worst_joint->worst_result.acceptable() ? std::string("Stable.") : worst_joint->worst_result.failure));
    reports::XyChart qc{"Joint angle",
                        {"Time", "s", false},
                        {"Angle", "rad", false},
                        {{"q", tr.t_s, tr.q_rad, reports::SeriesMode::kAuto, {}},
                         {"reference", tr.t_s, tr.q_ref_rad, reports::SeriesMode::kAuto, {}}},
                        ""};
    reports::XyChart tc{"Torques",
                        {"Time", "s", false},
                        {"Torque", "N·m", false},
                        {{"user", tr.t_s, tr.tau_user_nm, reports::SeriesMode::kAuto, {}},
                         {"wall", tr.t_s, tr.tau_env_nm, reports::SeriesMode::kAuto, {}}},
                        ""};
    reports::XyChart vc{"Valve command",
                        {"Time", "s", false},
                        {"Command", "V", false},
                        {{"valve", tr.t_s, tr.valve_v, reports::SeriesMode::kAuto, {}}},
                        ""};
    ws.addLineChart(std::move(qc));
    ws.addLineChart(std::move(tc));
    ws.addLineChart(std::move(vc));
  }

  // The paper's claim.
  const bool any_claim = std::any_of(out.joints.begin(), out.joints.end(),
                                     [](const design::JointValidationResult& o) { return o.has_claim; });
  if (any_claim) {
    reports::Section& pc = report.addSection("The paper's claim, measured");
    pc.addParagraph(
        "DTS paper section 3.3: the simple torque controller shows a large command spike as the joint begins to move, "
        "which the admittance controller reduces, allowing higher gains and stiffer walls. Measured here at equal "
        "free-space transparency: the torque PID's gains (ratios from the gains file) are scaled until its RMS user "
        "torque over the free move equals the admittance controller's; then both are compared on the onset spike "
        "(first 0.1 s of the motion) and on the largest wall stiffness that stays stable in the nonlinear simulation.");
    reports::Table ct;
    ct.caption = "Admittance controller vs torque PID at equal free-space transparency";
    ct.columns = {"Joint",
                  "Controller",
                  "RMS user torque [N m]",
                  "Peak user torque [N m]",
                  "Onset peak valve [V]",
                  "Largest stable wall [N m/rad]",
                  "Note"};
    ct.significant_digits = 4;
    for (const design::JointValidationResult& o : out.joints) {
      if (!o.has_claim) continue;
      const std::string j = shortJointName(o.nominal.joint_name);
      const design::ControllerFigures& a = o.claim.admittance;
      const design::ControllerFigures& p = o.claim.torque_pid;
      ct.rows.push_back({j, "admittance", a.free_rms_user_torque_nm, a.free_peak_user_torque_nm, a.onset_peak_valve_v,
                         a.max_stable_wall_nm_per_rad, "gains file"});
      ct.rows.push_back({j, "torque PID", p.free_rms_user_torque_nm, p.free_peak_user_torque_nm, p.onset_peak_valve_v,
                         p.max_stable_wall_nm_per_rad,
                         (o.claim.matched ? "matched, kp " : "NOT matched (closest stable), kp ") +
                             fixed(o.claim.pid_kp_v_per_nm, 4) + " V/N m"});
    }
    pc.addTable(std::move(ct));
  }
}

void printOutcome(const design::ArmValidationResult& out, std::ostream& os) {
  os << std::left;
  for (const design::JointValidationResult& o : out.joints) {
    os << "  " << std::setw(5) << shortJointName(o.nominal.joint_name) << (o.pass ? "PASS" : "FAIL") << "  linear "
       << (o.linear.pass ? "ok" : "fail") << " (rho free " << fixed(o.linear.free.spectral_radius, 5) << ", wall "
       << fixed(o.linear.contact.spectral_radius, 5) << ", Ms " << fixed(o.linear.free.margins.peak_sensitivity, 3)
       << ", gain limit x" << fixed(o.linear.predicted_gain_limit, 3) << ")  Monte-Carlo " << o.monte_carlo.failures
       << "/" << o.monte_carlo.runs.size() << " failed";
    if (o.monte_carlo.sluggish > 0) os << " (" << o.monte_carlo.sluggish << " too sluggish)";
    if (o.monte_carlo.wall_not_reached > 0) os << " (wall not reached in " << o.monte_carlo.wall_not_reached << ")";
    os << "\n";
    if (!o.pass) os << "        " << o.verdict << "\n";
    if (o.has_claim) {
      os << "        paper claim: onset valve peak adm " << fixed(o.claim.admittance.onset_peak_valve_v, 3)
         << " V vs pid " << fixed(o.claim.torque_pid.onset_peak_valve_v, 3) << " V; largest stable wall adm "
         << fixed(o.claim.admittance.max_stable_wall_nm_per_rad, 4) << " vs pid "
         << fixed(o.claim.torque_pid.max_stable_wall_nm_per_rad, 4) << " N m/rad at RMS user torque "
         << fixed(o.claim.admittance.free_rms_user_torque_nm, 3) << " / "
         << fixed(o.claim.torque_pid.free_rms_user_torque_nm, 3) << " N m\n";
    }
  }
  os << "  wall time " << fixed(out.wall_s, 3) << " s (Monte-Carlo " << fixed(out.monte_carlo_wall_s, 3) << " s, "
     << out.threads << " threads)\n";
}

std::vector<std::string> jointList(const controllers::GainsConfig& gains, const std::string& text) {
  return gainsJointNames(gains, text.empty() ? std::vector<std::string>{} : splitList(text), "--joints");
}

}  // namespace

CLI::App* addValidateCommand(CLI::App& app, ValidateOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "validate",
      "Validate controller gains per joint: linear checks, then a seeded Monte-Carlo of nonlinear closed-loop "
      "simulations (free motion, then a virtual wall); exit 1 on FAIL");
  OptionDeclarer declare(*cmd, table);
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--plant", o.plant_config, "Plant YAML (default: config/dts_plant.yaml)");
  declare.file("--gains", o.gains_config, "Gains YAML (default: config/dts_gains.yaml)");
  declare.file("--ranges", o.ranges_config, "Monte-Carlo ranges YAML (default: config/dts_validation.yaml)");
  declare.folder("--out", o.out_dir, "Output folder")->capture_default_str();
  // The Monte-Carlo keeps every run's result (a few hundred bytes each): 100,000 runs per joint
  // stay below a gigabyte for the 7 joints.
  declare.integer("--samples", o.samples, "Monte-Carlo runs per joint (overrides the ranges file)", 1, 100000);
  declare.integer("--seed", o.seed, "Monte-Carlo seed (overrides the ranges file)", 0, 2147483647);
  declare.integer("--threads", o.threads, "Worker threads (0: one per core); results do not depend on it", 0, 256);
  declare.list("--joints", o.joints, "Comma-separated joints, e.g. EB,WR (default: every joint of the gains file)");
  declare.flag("--paper-claim", o.paper_claim,
               "Also measure the paper's claim (admittance vs torque PID at equal transparency) per joint");
  return cmd;
}

int runValidate(const ValidateOptions& o) {
  const arm::ArmModel model = arm::loadArmModel(configPathOr(o.arm_config, arm::defaultArmModelPath));
  const plant::PlantConfig plant_config =
      plant::loadPlantConfig(configPathOr(o.plant_config, plant::defaultPlantConfigPath), model);
  const controllers::GainsConfig gains =
      controllers::loadGainsConfig(configPathOr(o.gains_config, controllers::defaultGainsConfigPath), model);
  design::ValidationConfig config =
      design::loadValidationConfig(configPathOr(o.ranges_config, design::defaultValidationConfigPath));
  if (o.samples) config.samples = *o.samples;
  if (o.seed) config.seed = static_cast<std::uint64_t>(*o.seed);
  const std::vector<std::string> joints = jointList(gains, o.joints);
  std::cout << "fullarm validate: " << joints.size() << " joint(s), " << config.samples
            << " Monte-Carlo runs each, seed " << config.seed << "\n";
  design::ArmValidationOptions options;
  options.joints = joints;
  options.threads = o.threads;
  options.paper_claim = o.paper_claim;
  options.progress = o.progress;
  const design::ArmValidationResult out = design::validateArm(model, plant_config, gains, config, options);
  printOutcome(out, std::cout);

  reports::Report report("validate", "Stability validation of the joint controllers");
  int failed = 0;
  for (const design::JointValidationResult& j : out.joints) failed += j.pass ? 0 : 1;
  report.setVerdict(
      out.pass(), out.pass() ? "Every joint passed the linear checks and all " + std::to_string(config.samples) +
                                   " Monte-Carlo runs"
                             : std::to_string(failed) + " of " + std::to_string(out.joints.size()) + " joints failed");
  report.results()["validate"] = toJson(out);
  addToReport(out, report, "");
  writeReport(report, o.out_dir);
  std::cout << (out.pass() ? "PASS" : "FAIL")
            << "\nReport: " << (std::filesystem::absolute(o.out_dir) / "report.html").string() << "\n";
  return out.pass() ? 0 : 1;
}

ValidateDemoStep runValidateDemoStep(const arm::ArmModel& model, const std::filesystem::path& gains_path, int samples,
                                     reports::Report& report, core::Progress& progress) {
  const plant::PlantConfig plant_config = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  const controllers::GainsConfig gains = controllers::loadGainsConfig(gains_path, model);
  design::ValidationConfig config = design::loadValidationConfig(design::defaultValidationConfigPath());
  config.samples = samples;
  design::ArmValidationOptions options;
  options.paper_claim = true;
  options.paper_claim_joints = {"EB"};
  options.progress = &progress;
  const design::ArmValidationResult out = design::validateArm(model, plant_config, gains, config, options);
  printOutcome(out, std::cout);
  report.results()["validate"] = toJson(out);
  addToReport(out, report, "validate_");
  int failed = 0;
  for (const design::JointValidationResult& j : out.joints) failed += j.pass ? 0 : 1;
  ValidateDemoStep step;
  step.pass = out.pass();
  step.detail = std::to_string(out.joints.size() - static_cast<std::size_t>(failed)) + " of " +
                std::to_string(out.joints.size()) + " joints pass (" + std::to_string(samples) +
                " Monte-Carlo runs per joint, " + fixed(out.wall_s, 3) + " s)";
  return step;
}

}  // namespace fullarm::app
