#include "identify_command.hpp"

#include <algorithm>
#include <cmath>
#include <complex>
#include <functional>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "cli_values.hpp"
#include "command_device.hpp"
#include "exit_codes.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/hil/io_backend.hpp"
#include "fullarm/hil/simulated_arm.hpp"
#include "fullarm/identification/excitation.hpp"
#include "fullarm/identification/experiment.hpp"
#include "fullarm/identification/experiment_lcm.hpp"
#include "fullarm/identification/frf.hpp"
#include "fullarm/identification/grey_box.hpp"
#include "fullarm/identification/identification_config.hpp"
#include "fullarm/identification/identified_model.hpp"
#include "fullarm/identification/identified_plant.hpp"
#include "fullarm/identification/joint_groups.hpp"
#include "fullarm/identification/signal_csv.hpp"
#include "fullarm/identification/validation.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "output_files.hpp"

namespace fullarm::app {
namespace {

namespace id = identification;

constexpr double kSamplePeriod_s = 1.0e-3;  // the loop's 1 kHz
constexpr double kBandHz = 30.0;            // excitation band (PRBS flat band, multisine top)
constexpr int kLatencySamples = 1;          // the simulated DTS's I/O latency
constexpr std::size_t kMaxPlotPoints = 1000;
constexpr std::size_t kMinLogSamples = 64;  // the shortest experiment fitted or validated
// --hold-angle's range before the joint is known (a turn either way); the joint's own limits less
// the experiment's margin are checked once the plant file is read.
constexpr double kMaxHoldAngleRad = 2.0 * std::numbers::pi;
// Why the move to --hold-angle on the real arm needs --confirm-arm-motion.
constexpr const char* kHoldMoveOnTheArm =
    "the joint's hold moves it on the real arm, up to its whole range, with no check for self-collision or the "
    "arm's surroundings; clear the workspace, then give --confirm-arm-motion";
constexpr const char* kIdentifiedFile = "identified.yaml";
constexpr const char* kIdentifiedPlantFile = "identified_plant.yaml";
constexpr const char* kFitLog = "experiment_fit";
constexpr const char* kValidationLog = "experiment_validation";

// A written experiment log's file name: `base` with the format's extension.
std::string logFileName(const char* base, const std::string& format) {
  return std::string(base) + (format == "lcm" ? ".lcm" : ".csv");
}

// One experiment: its log, where it came from and how it ended.
struct Experiment {
  std::string name;  // file name (written or read)
  id::SignalTable log;
  id::ExperimentData data;
  bool completed = true;
  std::string stop_reason;
  // The arm's posture during the experiment (model order): the default posture with every held
  // joint the log names (its `held_<joint>_rad` column) at its mean angle.
  Eigen::VectorXd posture;
};

// Everything a run produced, for the report and the summary.
struct Outcome {
  std::string joint;
  std::string source;  // the back-end ("sim", "fakedaq", "comedi", "lcm") or "logs"
  std::vector<Experiment> fit_experiments;
  Experiment validation;
  id::GreyModel start;
  std::string start_source;
  id::IdentificationConfig config;
  id::FitResult fit;
  id::ModelValidation validation_result;
  double wall_s = 0.0;
  bool plant_written = false;              // identified_plant.yaml
  std::string plant_note;                  // why it was not written
  std::vector<std::string> plant_notes;    // groups it carries only approximately
  double start_link_inertia = 0.0;         // the link's inertia at the start's posture [kg m^2]
  std::optional<double> start_gravity_nm;  // the gravity load there (none with --start)
  bool neighbours_held = false;            // the fitted log records held joints (kHeldNeighboursNote)
};

// The experiment a log holds, with the hydraulic torque of its chamber pressures (where logged)
// through the driven joint's geometry.
id::ExperimentData dataFromLog(const id::SignalTable& log, const std::string& file, const plant::JointParams& driven) {
  try {
    id::ExperimentData data = id::experimentFromLog(log);
    id::addHydraulicTorque(data, log, driven);
    return data;
  } catch (const std::invalid_argument& e) {
    throw core::ConfigError(file, "", e.what());
  }
}

// The posture an experiment ran in (model order): the default posture with each held joint of the
// log at its mean angle over the log. A column naming no joint of the arm model, or the driven
// joint (whose angle is `q_rad`), is bad input naming the file and the column.
Eigen::VectorXd postureOfLog(const arm::ArmModel& model, const id::SignalTable& log, int driven_joint,
                             const std::string& file) {
  Eigen::VectorXd posture = model.defaultPosture();
  for (const id::HeldAngle& held : id::heldAngles(log)) {
    const int index = model.jointIndex(held.joint);
    const std::string column = id::heldAngleColumn(held.joint);
    if (index < 0) {
      throw core::ConfigError(file, column,
                              "'" + held.joint + "' is not a joint of the arm model (" +
                                  model.source.filename().string() + "): expected a held joint's angle");
    }
    if (index == driven_joint) {
      throw core::ConfigError(
          file, column, "names the identified joint, whose angle is the column q_rad: expected a held joint's angle");
    }
    posture[index] = held.mean_rad;
  }
  return posture;
}

// PRBS over [0, duration): one period of the shortest register whose period covers it, cut.
id::SampledSignal fitExcitation(double amplitude_v, double duration_s) {
  const int clock = id::prbsClockSamplesForBand(kBandHz, kSamplePeriod_s);
  const double periods_needed = duration_s / (clock * kSamplePeriod_s) + 1.0;
  const int order = std::clamp(static_cast<int>(std::ceil(std::log2(periods_needed))), 2, 24);
  id::SampledSignal s = id::prbs(amplitude_v, order, clock, 1, kSamplePeriod_s);
  const auto n = static_cast<std::size_t>(std::llround(duration_s / kSamplePeriod_s));
  if (s.value_v.size() > n) {
    s.value_v.resize(n);
    s.time_s.resize(n);
  }
  return s;
}

// Schroeder multisine, one period over the duration, from its fundamental (at least 0.2 Hz) to the band.
id::SampledSignal validationExcitation(double amplitude_v, double duration_s) {
  const double low = std::max(0.2, 1.0 / duration_s);
  return id::schroederMultisine(amplitude_v, low, kBandHz, duration_s, 1, kSamplePeriod_s).signal;
}

// The single-joint model leaves out the coupling of neighbours that are held rather than locked:
// said wherever the fitted logs record held joints (every device that holds the whole arm, and
// logs recorded on one).
constexpr const char* kHeldNeighboursNote =
    "the other joints were held, not locked (the fitted log records their angles): their coupling "
    "through the arm's inertia and their holds is not in the single-joint model, and the groups carry it, "
    "by an amount that depends on the posture (on the simulated DTS with every joint held, the elbow's "
    "groups within 5 % at the scene's ready posture and up to 51 % off with the upper arm hanging; "
    "docs/identification.md)";

// Writes an experiment's log (file name, log) to the output folder as soon as the run ends, before
// anything that follows can fail; a run that stopped early keeps what it logged.
using KeepLog = std::function<void(const std::string&, const id::SignalTable&)>;

void keepLog(const std::string& name, const id::ExperimentResult& result, const KeepLog& keep) {
  if (result.log.rows() > 0) keep(name, result.log);
}

Experiment experimentOf(const id::ExperimentResult& r, const std::string& name, const plant::JointParams& driven) {
  Experiment e;
  e.name = name;
  e.log = r.log;
  e.completed = r.completed;
  e.stop_reason = r.stop_reason;
  if (e.log.rows() < kMinLogSamples) {
    const std::string expected =
        ": expected a joint that can be held and excited about its hold angle (--hold-angle), with room "
        "inside its limits less the margin for the hold's droop and the excitation's drift (--amplitude)";
    constexpr std::string_view kNotRun = "not run: ";
    if (e.log.rows() == 0 && r.stop_reason.starts_with(kNotRun)) {
      throw core::ConfigError({}, "--joint",
                              "the experiment logging to " + name + " did not run: the one before it stopped (" +
                                  r.stop_reason.substr(kNotRun.size()) + ")" + expected);
    }
    throw core::ConfigError({}, "--joint",
                            "the experiment logging to " + name + " stopped after " + std::to_string(e.log.rows()) +
                                " samples (" + r.stop_reason + ")" + expected);
  }
  e.data = dataFromLog(e.log, name, driven);
  return e;
}

Experiment runSimExperiment(const arm::ArmModel& model, plant::PlantConfig plant_config, int joint,
                            const Eigen::VectorXd& posture, const id::SampledSignal& excitation, std::uint64_t seed,
                            const std::string& name, const KeepLog& keep) {
  plant_config.seed = seed;
  plant_config.solver.integrator = plant::IntegratorKind::kRodas3;  // the lockstep loop's integrator
  // The simulated plant can lock joints (the real arm cannot): only the driven joint is active, the
  // others stay rigidly at the posture, so the data show the joint alone rather than the joint
  // coupled to its neighbours through their holds and oil columns.
  const plant::JointParams driven = plant_config.joints[static_cast<std::size_t>(joint)];
  plant_config.joints = {driven};
  hil::IoBackendOptions io;
  io.io = hil::IoKind::kSim;
  io.period_s = kSamplePeriod_s;
  io.latency_samples = kLatencySamples;
  io.plant = &plant_config;
  io.posture = posture;
  hil::IoBackend backend(model, io);
  id::ExperimentOptions options;
  options.joint = 0;
  options.min_rad = driven.min_rad;
  options.max_rad = driven.max_rad;
  options.joint_names = {driven.name};  // the device serves the driven joint alone: no held columns
  const id::ExperimentResult result = id::runExperiment(backend.device(), excitation, options);
  keepLog(name, result, keep);
  return experimentOf(result, name, driven);
}

// The driven joint's index among the device's joints.
int deviceJointIndex(hil::IoDevice& device, int model_joint, const std::string& name, const std::string& io) {
  for (int k = 0; k < device.joints().size(); ++k) {
    if (device.joints().modelIndex(k) == model_joint) return k;
  }
  throw core::ConfigError({}, "--joint", "'" + name + "' is not a joint of the " + io + " device's channel map");
}

// The experiments on a device that stays built and active from the first to the last (the fake
// DAQ, the real arm, a plant node): every device joint held, the driven one excited in turn by
// each excitation, the holds continuing between them; the limits are the plant file's. Every
// experiment that logged anything keeps its log before one that stopped too early is refused.
std::vector<Experiment> runDeviceExperiments(const arm::ArmModel& model, CommandDevice& device, int device_joint,
                                             const plant::JointParams& driven, std::optional<double> hold_rad,
                                             const std::vector<id::SampledSignal>& excitations,
                                             const std::vector<std::string>& names, const KeepLog& keep) {
  id::ExperimentOptions options;
  options.joint = device_joint;
  options.min_rad = driven.min_rad;
  options.max_rad = driven.max_rad;
  options.hold_rad = hold_rad;
  options.before_read = device.pace;
  options.log_control_time = true;
  const arm::JointSelection& joints = device.backend->device().joints();
  for (int k = 0; k < joints.size(); ++k) {
    options.joint_names.push_back(model.joints[static_cast<std::size_t>(joints.modelIndex(k))].name);
  }
  const int model_joint = joints.modelIndex(device_joint);
  const std::vector<id::ExperimentResult> results = id::runExperiments(device.backend->device(), excitations, options);
  for (std::size_t e = 0; e < results.size(); ++e) keepLog(names[e], results[e], keep);
  std::vector<Experiment> experiments;
  for (std::size_t e = 0; e < results.size(); ++e) {
    Experiment x = experimentOf(results[e], names[e], driven);
    x.posture = postureOfLog(model, x.log, model_joint, names[e]);
    experiments.push_back(std::move(x));
  }
  return experiments;
}

// Options that mean nothing with the chosen source are refused, not ignored.
void checkOptionCombination(const IdentifyOptions& o) {
  const auto refuse = [](const char* option, const std::string& why) { throw core::ConfigError({}, option, why); };
  if (!o.logs.empty()) {
    if (!o.lcm_url.empty()) refuse("--lcm-url", "no experiment runs with --log");
    if (o.log_format_given) refuse("--log-format", "no experiment log is written with --log (it reads either format)");
    if (!o.daq_config.empty())
      refuse("--daq-config", "a channel map is read only when experiments run (not with --log)");
    if (!o.hil_config.empty())
      refuse("--hil-config", "the loop configuration is read only when experiments run (not with --log)");
    if (o.seed) refuse("--seed", "seeds the simulated sensors' noise: no experiment runs with --log");
    if (o.hold_angle_rad) refuse("--hold-angle", "no experiment runs with --log (the logs' angles are what they are)");
    if (o.confirm_arm_motion) refuse("--confirm-arm-motion", "no experiment runs with --log: nothing moves");
    return;
  }
  const hil::IoKind kind = commandIoKind(o.io);
  if (kind == hil::IoKind::kSim) {
    if (!o.daq_config.empty()) refuse("--daq-config", "only --io fakedaq and --io comedi read a channel map");
    if (!o.hil_config.empty()) {
      refuse("--hil-config",
             "--io sim simulates the joint alone at 1 kHz with its own settings; only --io fakedaq, comedi and lcm "
             "read the loop configuration");
    }
  }
  if (kind == hil::IoKind::kComedi && o.seed) {
    refuse("--seed", "seeds the simulated sensors' noise: the real arm (--io comedi) has none");
  }
  if (o.confirm_arm_motion && !(o.hold_angle_rad && (kind == hil::IoKind::kComedi || kind == hil::IoKind::kLcm))) {
    refuse("--confirm-arm-motion",
           "only the move to --hold-angle on the real arm (--io comedi, or --io lcm on a node serving it) needs it");
  }
  if (kind == hil::IoKind::kComedi && o.hold_angle_rad && !o.confirm_arm_motion) {
    refuse("--confirm-arm-motion", std::string("is required with --hold-angle on --io comedi: ") + kHoldMoveOnTheArm);
  }
  if (kind == hil::IoKind::kLcm) {
    if (o.seed) refuse("--seed", "the plant node seeds its own sensors' noise (fullarm plant serve --seed)");
    if (!o.daq_config.empty()) refuse("--daq-config", "the plant node reads its own channel map, if any");
  } else if (!o.lcm_url.empty()) {
    refuse("--lcm-url", "only --io lcm talks to a plant node");
  }
}

// The start's values must lie inside the settings' bounds (the fit refuses otherwise).
void checkStartInBounds(const id::GreyModel& start, const id::IdentificationConfig& config,
                        const std::string& start_source) {
  for (int i = 0; i < id::kGreyParams; ++i) {
    const id::ParamSpec& p = config.fit.params[static_cast<std::size_t>(i)];
    const double v = start.value[static_cast<std::size_t>(i)];
    if (!(v >= p.min && v <= p.max)) {
      throw core::ConfigError(config.source, std::string("parameters.") + id::greyParamName(i),
                              "the start (" + start_source + ") has " + numberText(v) + ", outside the bounds [" +
                                  numberText(p.min) + ", " + numberText(p.max) + "]: expected bounds that hold it");
    }
  }
}

// The linearised model's response from valve command to angle at `f_hz` (Coulomb friction left
// out): q/u = a K_h S(s) e^{-s d T} / ((s + K_h c)(J s^2 + b s) + K_h s), S the spool's lag.
std::complex<double> modelAngleResponse(const id::GreyModel& m, double f_hz) {
  using C = std::complex<double>;
  const C s(0.0, 2.0 * std::numbers::pi * f_hz);
  const auto& v = m.value;
  const double kh = v[id::kStiffness];
  C num = v[id::kFlowGain] * kh * std::exp(-s * (m.delay_samples * kSamplePeriod_s));
  if (m.spool_hz > 0.0) {
    const double wn = 2.0 * std::numbers::pi * m.spool_hz;
    num *= wn * wn / (s * s + 2.0 * m.spool_damping * wn * s + wn * wn);
  }
  const C den = (s + kh * v[id::kLeakage]) * (v[id::kInertia] * s * s + v[id::kViscous] * s) + kh * s;
  return num / den;
}

template <typename T>
std::vector<T> every(const std::vector<T>& v, std::size_t stride) {
  std::vector<T> out;
  for (std::size_t i = 0; i < v.size(); i += stride) out.push_back(v[i]);
  return out;
}

bool allFinite(const id::FitResult& fit) {
  for (int i = 0; i < id::kGreyParams; ++i) {
    const auto k = static_cast<std::size_t>(i);
    if (!std::isfinite(fit.model.value[k]) || !std::isfinite(fit.standard_error[k])) return false;
  }
  return std::isfinite(fit.cost);
}

nlohmann::json correlationJson(const id::CorrelationTest& t) {
  return {{"label", t.label}, {"bound", t.bound}, {"outside", t.outside}, {"lags", t.lags.size()}};
}

void addToReport(const Outcome& o, reports::Report& report, const std::string& heading) {
  const auto& cfg = o.config;
  nlohmann::json params = nlohmann::json::object();
  for (int i = 0; i < id::kGreyParams; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const id::ParamSpec& p = cfg.fit.params[k];
    params[id::greyParamName(i)] = {{"value", o.fit.model.value[k]},
                                    {"standard_error", o.fit.standard_error[k]},
                                    {"start", o.start.value[k]},
                                    {"min", p.min},
                                    {"max", p.max},
                                    {"free", p.free},
                                    {"at_bound", p.free && (o.fit.model.value[k] <= p.min * (1.0 + 1e-9) ||
                                                            o.fit.model.value[k] >= p.max * (1.0 - 1e-9))}};
  }
  nlohmann::json experiments = nlohmann::json::array();
  const auto addExperiment = [&](const Experiment& e, const char* role) {
    experiments.push_back({{"file", e.name},
                           {"role", role},
                           {"samples", e.log.rows()},
                           {"completed", e.completed},
                           {"stop_reason", e.stop_reason},
                           {"hold_gain_v_per_rad", e.data.hold_gain_v_per_rad},
                           {"hold_rad", e.data.hold_rad}});
    nlohmann::json held = nlohmann::json::object();
    for (const id::HeldAngle& h : id::heldAngles(e.log)) held[h.joint] = h.mean_rad;
    experiments.back()["held_joints_rad"] = held;
  };
  for (std::size_t i = 0; i < o.fit_experiments.size(); ++i) {
    addExperiment(o.fit_experiments[i], "fit");
    // The fit's initial state of this experiment (at rest where the settings hold it fixed).
    if (i < o.fit.initial_states.size()) {
      const id::InitialState& x0 = o.fit.initial_states[i];
      const id::InitialState se =
          i < o.fit.initial_state_standard_error.size() ? o.fit.initial_state_standard_error[i] : id::InitialState{};
      experiments.back()["initial_state"] = {{"speed_radps", x0.speed_radps},
                                             {"speed_standard_error", se.speed_radps},
                                             {"torque_offset_nm", x0.torque_offset_nm},
                                             {"torque_offset_standard_error", se.torque_offset_nm}};
    }
  }
  addExperiment(o.validation, "validation");
  const id::ModelValidation& v = o.validation_result;
  report.results()["identify"] = {
      {"joint", o.joint},
      {"source", o.source},
      {"neighbours_held", o.neighbours_held},
      {"start", o.start_source},
      {"start_link_inertia_kgm2", o.start_link_inertia},
      {"start_gravity_load_nm", o.start_gravity_nm ? nlohmann::json(*o.start_gravity_nm) : nlohmann::json(nullptr)},
      {"settings", cfg.source.string()},
      {"experiments", experiments},
      {"delay_samples", o.fit.model.delay_samples},
      {"parameters", params},
      {"cost", o.fit.cost},
      {"evaluations", o.fit.evaluations},
      {"fit_wall_s", o.fit.global_seconds + o.fit.polish_seconds},
      {"unidentifiable", o.fit.unidentifiable},
      {"identified_plant", o.plant_written ? nlohmann::json(kIdentifiedPlantFile) : nlohmann::json(nullptr)},
      {"identified_plant_refused", o.plant_note},
      {"identified_plant_notes", o.plant_notes},
      {"validation",
       {{"fit_angle_percent", v.angle.fit_percent},
        {"fit_torque_percent", v.torque.fit_percent},
        {"prediction_fit_angle_percent", v.angle.prediction_fit_percent},
        {"prediction_fit_torque_percent", v.torque.prediction_fit_percent},
        {"fit_hydraulic_torque_percent", v.has_hydraulic && std::isfinite(v.hydraulic_fit_percent)
                                             ? nlohmann::json(v.hydraulic_fit_percent)
                                             : nlohmann::json(nullptr)},
        {"prediction_fit_hydraulic_torque_percent", v.has_hydraulic && std::isfinite(v.hydraulic_prediction_fit_percent)
                                                        ? nlohmann::json(v.hydraulic_prediction_fit_percent)
                                                        : nlohmann::json(nullptr)},
        {"angle_autocorrelation", correlationJson(v.angle.autocorrelation)},
        {"angle_cross_correlation", correlationJson(v.angle.cross_correlation)},
        {"torque_autocorrelation", correlationJson(v.torque.autocorrelation)},
        {"torque_cross_correlation", correlationJson(v.torque.cross_correlation)},
        {"prediction_process_scale", v.process_scale},
        {"pass", v.pass},
        {"failures", v.failures}}}};

  reports::Section& section = report.addSection(heading);
  std::ostringstream intro;
  intro << "Joint " << o.joint << ": the reduced hydraulic joint model (docs/identification.md) fitted by output "
        << "error to " << o.fit_experiments.size() << " closed-loop experiment(s) "
        << (o.source == "sim"       ? "on the simulated DTS (the joint alone, its neighbours locked; a PRBS to 30 Hz "
                                      "added to the valve command about a proportional position hold)"
            : o.source == "fakedaq" ? "through the fake DAQ (the comedi back-end on the simulated DTS, its neighbours "
                                      "locked and the board serving the driven joint's channels; a PRBS to 30 Hz added "
                                      "to the valve command about a proportional position hold)"
            : o.source == "comedi"  ? "on the arm through the Comedi board (every other joint held; a PRBS to 30 Hz "
                                      "added to the valve command about a proportional position hold)"
            : o.source == "lcm" ? "on a plant node over LCM (fullarm plant serve, every other joint held; a PRBS to "
                                  "30 Hz added to the valve command about a proportional position hold)"
                                : "read from recorded logs")
        << ", validated on a held-out experiment by pure simulation (its fit and its residual's independence of the "
           "past excitation judged) and one-step-ahead prediction (its fit reported, its errors' whiteness judged)"
        << (o.source != "logs" ? " (a Schroeder multisine to 30 Hz)" : " (the last log)")
        << ". Fit start: " << o.start_source << ". " << o.fit.evaluations << " closed-loop simulations and "
        << o.fit.sensitivity_evaluations << " with forward sensitivities, cost " << std::setprecision(4) << o.fit.cost
        << ".";
  section.addParagraph(intro.str());
  {
    std::ostringstream posture;
    posture << std::setprecision(4) << "Posture: " << o.joint << " at its hold angle "
            << o.fit_experiments.front().data.hold_rad << " rad";
    const std::vector<id::HeldAngle> held = id::heldAngles(o.fit_experiments.front().log);
    if (held.empty()) {
      posture << ", every other joint at the arm's default posture";
    } else {
      posture << ", the held joints at their mean angles in " << o.fit_experiments.front().name << " (";
      for (std::size_t k = 0; k < held.size(); ++k)
        posture << (k > 0 ? ", " : "") << held[k].joint << " " << held[k].mean_rad;
      posture << " rad), any other at the arm's default posture";
    }
    posture << ": there the link's inertia is " << o.start_link_inertia << " kg m^2";
    if (o.start_gravity_nm) posture << " and its gravity load " << *o.start_gravity_nm << " N m, the fit's start";
    posture << ".";
    section.addParagraph(posture.str());
    if (o.neighbours_held) {
      std::string note = kHeldNeighboursNote;
      note[0] = 'T';
      section.addParagraph(note + ".");
    }
  }
  section.addParagraph(
      o.plant_written
          ? std::string("Plant file: ") + kIdentifiedPlantFile +
                " is the starting plant with this joint's rated flow, dead volumes, internal leakage, actuator "
                "inertia and friction set so that its own groups at the hold angle are the identified ones "
                "(docs/identification.md); plant, tune, validate and run read it with --plant."
          : std::string("No plant file: ") + o.plant_note);
  for (const std::string& n : o.plant_notes) section.addParagraph("Plant file, approximate: " + n + ".");
  for (const Experiment& e : o.fit_experiments) {
    if (!e.completed) section.addParagraph("Fit experiment " + e.name + " stopped early: " + e.stop_reason);
  }
  if (!o.validation.completed) {
    section.addParagraph("Held-out experiment " + o.validation.name + " stopped early: " + o.validation.stop_reason);
  }

  // Parameter table with 95 % confidence intervals.
  reports::Table table;
  table.caption = "Identified parameter groups (delay " + std::to_string(o.fit.model.delay_samples) +
                  " samples); 95 % interval = value +- 1.96 standard errors from the Jacobian at the optimum";
  table.columns = {"Parameter", "Start", "Identified", "Standard error", "95 % low", "95 % high", "Bounds", "Note"};
  for (int i = 0; i < id::kGreyParams; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const id::ParamSpec& p = cfg.fit.params[k];
    const double val = o.fit.model.value[k];
    const double se = o.fit.standard_error[k];
    std::string note = p.free ? "" : "fixed";
    if (p.free && (val <= p.min * (1.0 + 1e-9) || val >= p.max * (1.0 - 1e-9))) note = "at a bound";
    table.rows.push_back({id::greyParamName(i), o.start.value[k], val, se, val - 1.96 * se, val + 1.96 * se,
                          "[" + numberText(p.min) + ", " + numberText(p.max) + "]", note});
  }
  table.significant_digits = 4;
  section.addTable(std::move(table));
  // Each fitted experiment's initial state (the speed and the hydraulic torque's excess over the
  // static load at the first simulated reading), estimated with the groups or held at rest.
  if (cfg.fit.initial_speed.free || cfg.fit.initial_torque_offset.free) {
    reports::Table states;
    states.caption = "Initial state of each fitted experiment, estimated with the groups (a fixed one is at rest)";
    states.columns = {"Experiment", "Initial speed [rad/s]", "Standard error", "Torque offset [N m]", "Standard error"};
    for (std::size_t i = 0; i < o.fit_experiments.size() && i < o.fit.initial_states.size(); ++i) {
      const id::InitialState& x0 = o.fit.initial_states[i];
      const id::InitialState se =
          i < o.fit.initial_state_standard_error.size() ? o.fit.initial_state_standard_error[i] : id::InitialState{};
      states.rows.push_back(
          {o.fit_experiments[i].name, x0.speed_radps, se.speed_radps, x0.torque_offset_nm, se.torque_offset_nm});
    }
    states.significant_digits = 4;
    section.addTable(std::move(states));
  }
  if (o.fit.unidentifiable.empty()) {
    section.addParagraph(
        "Unidentifiable directions: none (no singular value of the scaled Jacobian below 1e-6 of "
        "the largest).");
  } else {
    std::string text = "Unidentifiable directions (the data cannot determine these combinations):";
    for (const std::string& d : o.fit.unidentifiable) text += " " + d + ";";
    section.addParagraph(text);
  }

  // Time-domain overlay on the held-out experiment.
  const id::ExperimentData& d = o.validation.data;
  const id::Simulation sim = id::simulateClosedLoop(o.fit.model, d);
  const std::size_t stride = std::max<std::size_t>(1, d.q_rad.size() / kMaxPlotPoints);
  std::vector<double> t(d.q_rad.size());
  for (std::size_t k = 0; k < t.size(); ++k) t[k] = static_cast<double>(k) * d.sample_period_s;
  const auto overlay = [&](const char* title, const char* label, const char* unit, const std::vector<double>& measured,
                           const std::vector<double>& simulated) {
    reports::XyChart c;
    c.title = title;
    c.x_axis = {"Time", "s"};
    c.y_axis = {label, unit};
    c.series.push_back({"measured", every(t, stride), every(measured, stride)});
    if (sim.ok && simulated.size() == measured.size()) {
      c.series.push_back({"simulated (identified model)", every(t, stride), every(simulated, stride)});
    }
    c.caption = "Held-out experiment " + o.validation.name + "; the model sees only the excitation (pure simulation).";
    section.addLineChart(std::move(c));
  };
  overlay("Held-out experiment: angle, measured vs simulated", "Angle", "rad", d.q_rad, sim.q_rad);
  overlay("Held-out experiment: load-cell torque, measured vs simulated", "Torque", "N·m", d.tau_nm, sim.tau_nm);
  if (d.tau_hydraulic_nm.size() == d.q_rad.size()) {
    overlay("Held-out experiment: hydraulic torque from the chamber pressures, measured vs simulated", "Torque", "N·m",
            d.tau_hydraulic_nm, sim.tau_hydraulic_nm);
  }

  // FRF from valve command to angle, with the excitation as instrument.
  const std::size_t n = d.q_rad.size();
  int segment = 64;
  while (static_cast<std::size_t>(segment) * 2 <= std::min<std::size_t>(n / 4, 4096)) segment *= 2;
  try {
    id::FrfOptions fo;
    fo.segment_samples = segment;
    const id::FrfEstimate frf = id::estimateFrf(d.excitation_v, d.command_v, d.q_rad, d.sample_period_s, fo);
    reports::XyChart mag;
    mag.title = "Frequency response, valve command to angle (held-out experiment)";
    mag.x_axis = {"Frequency", "Hz", true};
    mag.y_axis = {"|q/u|", "dB"};
    reports::Series inst{"S_ry / S_ru (excitation as instrument)", {}, {}};
    reports::Series h1{"H1 = S_uy / S_uu (biased under feedback)", {}, {}};
    reports::Series model{"identified model (linearised, no Coulomb friction)", {}, {}};
    reports::XyChart coh;
    coh.title = "Coherence (held-out experiment)";
    coh.x_axis = {"Frequency", "Hz", true};
    coh.y_axis = {"Coherence", ""};
    reports::Series c_ry{"excitation to angle", {}, {}};
    reports::Series c_ru{"excitation to command", {}, {}};
    reports::Series c_uy{"command to angle", {}, {}};
    for (std::size_t k = 0; k < frf.frequency_hz.size(); ++k) {
      const double f = frf.frequency_hz[k];
      if (f > 2.0 * kBandHz) break;
      inst.x.push_back(f);
      inst.y.push_back(id::magnitudeDb(frf.instrument[k]));
      h1.x.push_back(f);
      h1.y.push_back(id::magnitudeDb(frf.h1[k]));
      model.x.push_back(f);
      model.y.push_back(id::magnitudeDb(modelAngleResponse(o.fit.model, f)));
      c_ry.x.push_back(f);
      c_ry.y.push_back(frf.coherence_ry[k]);
      c_ru.x.push_back(f);
      c_ru.y.push_back(frf.coherence_ru[k]);
      c_uy.x.push_back(f);
      c_uy.y.push_back(frf.coherence_uy[k]);
    }
    mag.series = {inst, h1, model};
    mag.caption = "Welch estimate, " + std::to_string(frf.segments) + " Hann-windowed segments of " +
                  std::to_string(segment) + " samples; trust it where the excitation-angle coherence is high.";
    section.addLineChart(std::move(mag));
    coh.series = {c_ry, c_ru, c_uy};
    section.addLineChart(std::move(coh));
  } catch (const std::invalid_argument& e) {
    section.addParagraph(std::string("No frequency response: ") + e.what());
  }

  // Residual tests with their 99 % bounds.
  const auto correlationChart = [&](const char* title, const char* x_label, const char* residual, bool cross) {
    reports::XyChart c;
    c.title = title;
    c.x_axis = {x_label, "samples"};
    c.y_axis = {"Normalised correlation", ""};
    double bound = 0.0;
    double lo = 0.0, hi = 0.0;
    for (const auto& [name, ch] : {std::pair<const char*, const id::ChannelValidation*>{"angle", &v.angle},
                                   std::pair<const char*, const id::ChannelValidation*>{"torque", &v.torque}}) {
      const id::CorrelationTest& test = cross ? ch->cross_correlation : ch->autocorrelation;
      reports::Series s{std::string(name) + " " + residual, {}, test.values};
      for (int lag : test.lags) s.x.push_back(lag);
      s.mode = reports::SeriesMode::kLinesMarkers;
      if (!test.lags.empty()) {
        lo = std::min(lo, static_cast<double>(test.lags.front()));
        hi = std::max(hi, static_cast<double>(test.lags.back()));
      }
      bound = test.bound;
      c.series.push_back(std::move(s));
    }
    c.series.push_back({"99 % bound", {lo, hi}, {bound, bound}});
    c.series.push_back({"-99 % bound", {lo, hi}, {-bound, -bound}});
    section.addLineChart(std::move(c));
  };
  correlationChart("Whiteness: autocorrelation of the one-step prediction errors (held-out experiment)", "Lag",
                   "prediction error", false);
  correlationChart(
      "Independence: cross-correlation of the simulation residual with the past excitation (held-out experiment)",
      "Lag", "simulation residual", true);

  reports::Table vt;
  vt.caption = "Validation on the held-out experiment (thresholds from " + cfg.source.filename().string() +
               "): the simulation sees only the excitation and is judged; the one-step prediction (a Kalman filter "
               "on the readings up to the previous sample, correcting the model at every sample, its process noise "
               "the reference levels times " +
               numberText(v.process_scale) +
               ", estimated from the held-out record) is reported beside it; the simulation residual is judged for "
               "independence of the past excitation, the prediction errors for whiteness";
  vt.columns = {"Channel",
                "Simulation fit [%]",
                "Required simulation fit [%]",
                "One-step prediction fit [%]",
                "Prediction errors: autocorrelation lags outside",
                "Simulation residual: cross-correlation lags outside"};
  const auto outside = [](const id::CorrelationTest& test) {
    return std::to_string(test.outside) + " / " + std::to_string(test.lags.size());
  };
  vt.rows.push_back({"angle", v.angle.fit_percent, cfg.validation.min_fit_angle_percent, v.angle.prediction_fit_percent,
                     outside(v.angle.autocorrelation), outside(v.angle.cross_correlation)});
  vt.rows.push_back({"torque", v.torque.fit_percent, cfg.validation.min_fit_torque_percent,
                     v.torque.prediction_fit_percent, outside(v.torque.autocorrelation),
                     outside(v.torque.cross_correlation)});
  if (v.has_hydraulic) {
    const auto percent = [](double x) { return std::isfinite(x) ? reports::Cell(x) : reports::Cell(std::string("-")); };
    vt.rows.push_back({"hydraulic torque (chamber pressures; reported, not judged)", percent(v.hydraulic_fit_percent),
                       std::string("-"), percent(v.hydraulic_prediction_fit_percent), std::string("-"),
                       std::string("-")});
  }
  vt.significant_digits = 4;
  section.addTable(std::move(vt));
  if (v.pass) {
    section.addParagraph("Verdict: the identified model passes every validation threshold.");
  } else {
    std::string text = "Verdict: the identified model fails its validation:";
    for (const std::string& f : v.failures) text += " " + f;
    section.addParagraph(text);
  }
}

std::string verdictText(const Outcome& o) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(1) << o.joint << " identified: held-out simulation fit angle "
    << o.validation_result.angle.fit_percent << " %, torque " << o.validation_result.torque.fit_percent
    << " %; one-step prediction fit angle " << o.validation_result.angle.prediction_fit_percent << " %, torque "
    << o.validation_result.torque.prediction_fit_percent << " %";
  if (o.validation_result.has_hydraulic) {
    s << "; hydraulic torque from the chamber pressures " << o.validation_result.hydraulic_fit_percent << " %";
  }
  s << " (" << (o.validation_result.pass ? "passes its validation" : "fails its validation") << ")";
  return s.str();
}

// The whole identification: experiments (or logs), fit, validation; the logs and identified.yaml
// written into `out`.
Outcome identify(const IdentifyOptions& o, const std::filesystem::path& out, core::Progress& progress,
                 std::ostream& text) {
  const auto started = std::chrono::steady_clock::now();
  checkOptionCombination(o);
  const arm::ArmModel model = arm::loadArmModel(configPathOr(o.arm_config, arm::defaultArmModelPath));
  const plant::PlantConfig plant_config =
      plant::loadPlantConfig(configPathOr(o.plant_config, plant::defaultPlantConfigPath), model);
  Outcome r;
  r.config = id::loadIdentificationConfig(configPathOr(o.settings, id::defaultIdentificationConfigPath));
  int joint = 0;
  try {
    joint = plant::findPlantJoint(plant_config, o.joint);
  } catch (const core::ConfigError& e) {
    throw core::ConfigError({}, "--joint", e.message());
  }
  const plant::JointParams& jp = plant_config.joints[static_cast<std::size_t>(joint)];
  r.joint = jp.name;
  const int model_joint = model.jointIndex(jp.name);
  if (model_joint < 0) throw core::ConfigError({}, "--joint", "'" + o.joint + "' is not a joint of the arm model");

  if (o.hold_angle_rad) {
    const double margin = id::ExperimentOptions{}.limit_margin_rad;
    const double lo = jp.min_rad + margin;
    const double hi = jp.max_rad - margin;
    if (!(*o.hold_angle_rad >= lo && *o.hold_angle_rad <= hi)) {
      throw core::ConfigError({}, "--hold-angle",
                              numberText(*o.hold_angle_rad) + " rad is outside " + jp.name + "'s limits " +
                                  numberText(jp.min_rad) + ".." + numberText(jp.max_rad) + " rad less the margin of " +
                                  numberText(margin) + " rad: expected " + numberText(lo) + ".." + numberText(hi) +
                                  " rad");
    }
  }

  progress.begin("identify", 0);
  if (o.logs.empty()) {
    r.source = o.io;
    const hil::IoKind kind = commandIoKind(o.io);
    const auto seed = static_cast<std::uint64_t>(o.seed.value_or(1));
    Eigen::VectorXd posture = model.defaultPosture();
    // The simulated DTS starts at the hold angle; a device moves the joint there (runExperiments).
    if (kind == hil::IoKind::kSim && o.hold_angle_rad) posture[model_joint] = *o.hold_angle_rad;
    const std::string fit_log = logFileName(kFitLog, o.log_format);
    const std::string validation_log = logFileName(kValidationLog, o.log_format);
    const id::SampledSignal fit_excitation = fitExcitation(o.amplitude_v, o.duration_s);
    const id::SampledSignal validation_excitation = validationExcitation(o.amplitude_v, o.duration_s);
    const KeepLog keep = [&](const std::string& name, const id::SignalTable& log) {
      const std::filesystem::path file = out / name;
      if (o.log_format == "lcm") {
        id::ExperimentLogInfo info;
        info.command_line = o.command_line;
        info.source = o.io;
        info.joint = r.joint;
        info.sample_period_s = kSamplePeriod_s;
        writeOutput(file, [&] { id::writeExperimentLcmLog(file, log, info); });
      } else {
        writeOutput(file, [&] { id::writeSignalCsv(file, log); });
      }
    };
    // A driven joint resting within the margin of a limit is refused before anything moves; the
    // hold angle is what moves it away.
    try {
      if (kind == hil::IoKind::kSim) {
        progress.step("experiment 1 of 2 (fit): PRBS on " + shortJointName(r.joint));
        r.fit_experiments.push_back(
            runSimExperiment(model, plant_config, joint, posture, fit_excitation, seed, fit_log, keep));
        progress.step("experiment 2 of 2 (held out): multisine on " + shortJointName(r.joint));
        r.validation = runSimExperiment(model, plant_config, joint, posture, validation_excitation, seed + 1,
                                        validation_log, keep);
      } else {
        // One device for both experiments, as on the real arm, active from the first to the last:
        // the held-out experiment continues the fitted one's holds. A gravity load drifts the
        // joint off its hold over an experiment, by the hold's droop and more; a hold taken up
        // anew would start where it drifted to (lower each time, into the limit's margin) after
        // letting it sag through the ramp-in. On the fake DAQ the simulated DTS locks the other
        // joints, as --io sim does, and the board serves the driven joint's channels: the data show
        // the joint alone (with every joint held instead, the neighbours' holds and the arm's
        // coupling enter the data, which the single-joint model does not describe;
        // docs/identification.md). The real arm holds them all.
        const std::unique_ptr<CommandDevice> device =
            openCommandDevice(kind, model, plant_config, posture, seed, o.daq_config, o.hil_config, kSamplePeriod_s,
                              kind == hil::IoKind::kFakeDaq ? jp.name : std::string(), o.lcm_url);
        checkNodeArmMotion(*device, o.hold_angle_rad.has_value(), o.confirm_arm_motion,
                           "--hold-angle on a node serving the real arm", kHoldMoveOnTheArm);
        const int device_joint = deviceJointIndex(device->backend->device(), model_joint, o.joint, o.io);
        // The run's loop reports nothing while it runs (no I/O there): the line says how long it
        // takes in control time, which the arm runs in real time.
        const double run_s = 2.0 * (id::ExperimentOptions{}.settle_s + o.duration_s);
        progress.step("experiments 1 and 2 of 2 (fit, held out): PRBS then multisine on " + shortJointName(r.joint) +
                      " through " + o.io + ", " + core::formatDuration(run_s) + " of control time" +
                      (o.hold_angle_rad ? " after the move to the hold angle" : ""));
        std::vector<Experiment> run =
            runDeviceExperiments(model, *device, device_joint, jp, o.hold_angle_rad,
                                 {fit_excitation, validation_excitation}, {fit_log, validation_log}, keep);
        r.fit_experiments.push_back(std::move(run[0]));
        r.validation = std::move(run[1]);
      }
    } catch (const id::ExperimentRefused& e) {
      throw core::ConfigError({}, "--hold-angle", e.what());
    }
  } else {
    r.source = "logs";
    if (o.logs.size() < 2) {
      throw core::ConfigError({}, "--log",
                              "expected at least two logs (all but the last are fitted, the last is held out), got 1");
    }
    for (std::size_t k = 0; k < o.logs.size(); ++k) {
      Experiment e;
      e.name = o.logs[k];
      if (id::isLcmLog(o.logs[k])) {
        // hil::RunLogError for a malformed log: bad input (exit 2)
        id::ExperimentLcmLog recorded = id::readExperimentLcmLog(o.logs[k]);
        if (recorded.info.joint != r.joint) {
          throw core::ConfigError(o.logs[k], "joint",
                                  "the log's experiment drove " + recorded.info.joint + ", --joint names " + r.joint);
        }
        if (!recorded.warning.empty()) text << "warning: " << recorded.warning << "\n";
        if (recorded.skipped > 0) {
          text << o.logs[k] << ": " << recorded.skipped << " events on other channels skipped\n";
        }
        e.log = std::move(recorded.table);
      } else {
        e.log = id::readSignalCsv(o.logs[k], id::kExperimentColumns);  // CsvFormatError: bad input (exit 2)
      }
      e.posture = postureOfLog(model, e.log, model_joint, o.logs[k]);
      if (e.log.rows() < kMinLogSamples) {
        throw core::ConfigError(o.logs[k], "",
                                std::to_string(e.log.rows()) + " samples: expected at least " +
                                    std::to_string(kMinLogSamples) + " to fit or validate");
      }
      e.data = dataFromLog(e.log, o.logs[k], jp);
      if (k + 1 < o.logs.size()) {
        r.fit_experiments.push_back(std::move(e));
      } else {
        r.validation = std::move(e);
      }
    }
  }
  r.neighbours_held = !id::heldAngles(r.fit_experiments.front().log).empty();
  // The start: a given model, or the plant joint's groups at the hold angle with the link's
  // inertia and gravity load there (the held joints at the angles the first fitted log records,
  // the others at the default posture).
  const double q_hold = r.fit_experiments.front().data.hold_rad;
  Eigen::VectorXd q =
      r.fit_experiments.front().posture.size() > 0 ? r.fit_experiments.front().posture : model.defaultPosture();
  q[model_joint] = q_hold;
  arm::ArmData arm_data(model);
  arm::computeMassMatrix(model, arm_data, q);
  const double link_inertia = arm_data.mass_matrix(model_joint, model_joint);
  r.start_link_inertia = link_inertia;
  if (!o.start.empty()) {
    const id::IdentifiedModel given = id::loadIdentifiedModel(o.start);
    r.start = given.model;
    r.start_source = o.start;
  } else {
    arm::computeGravityTorques(model, arm_data, q);
    r.start_gravity_nm = arm_data.tau_gravity[model_joint];
    r.start = id::greyModelFromJoint(jp, q_hold, link_inertia, arm_data.tau_gravity[model_joint], 1);
    // The gravity load's gradient at the hold angle (central difference), the known load stiffness.
    constexpr double kStep_rad = 1.0e-4;
    Eigen::VectorXd q_step = q;
    q_step[model_joint] = q_hold + kStep_rad;
    arm::computeGravityTorques(model, arm_data, q_step);
    const double tau_up = arm_data.tau_gravity[model_joint];
    q_step[model_joint] = q_hold - kStep_rad;
    arm::computeGravityTorques(model, arm_data, q_step);
    r.start.load_gradient_nm_per_rad = (tau_up - arm_data.tau_gravity[model_joint]) / (2.0 * kStep_rad);
    r.start_source = "the plant's groups of " + r.joint + " (" + plant_config.source.filename().string() + ")";
  }
  r.start.coulomb_smoothing_radps = r.config.coulomb_smoothing_radps;
  r.start.stribeck_velocity_radps = r.config.stribeck_velocity_radps;
  checkStartInBounds(r.start, r.config, r.start_source);

  id::FitOptions fit = r.config.fit;
  fit.threads = o.threads;
  fit.progress = [&progress](const std::string& line) { progress.step(line); };
  std::vector<id::ExperimentData> data;
  for (const Experiment& e : r.fit_experiments) data.push_back(e.data);
  progress.step("fit: " + std::to_string(data.size()) + " experiment(s)");
  r.fit = id::fitGreyModel(data, r.start, fit);
  progress.step("validation on the held-out experiment");
  r.validation_result = id::validateModel(r.fit.model, r.validation.data, r.config.validation);
  progress.end(r.validation_result.pass ? "passes its validation" : "fails its validation");

  id::IdentifiedModel identified;
  identified.joint = r.joint;
  identified.model = r.fit.model;
  identified.standard_error = r.fit.standard_error;
  writeTextFile(out / kIdentifiedFile, id::formatIdentifiedModelYaml(identified));
  // The plant with the identified joint's groups carried by its designated parameters.
  std::filesystem::remove(out / kIdentifiedPlantFile);
  try {
    plant::PlantConfig identified_plant = plant_config;
    const id::IdentifiedPlantJoint carried = id::plantJointWithGroups(jp, r.fit.model, q_hold, link_inertia);
    identified_plant.joints[static_cast<std::size_t>(joint)] = carried.joint;
    r.plant_notes = carried.notes;
    std::ostringstream hold;
    hold << std::setprecision(6) << q_hold;
    const std::vector<std::string> header = {
        plant_config.source.filename().string() + " with " + r.joint +
            "'s identified groups (identified.yaml, written by fullarm identify; docs/identification.md).",
        "Set from the groups at the hold angle " + hold.str() +
            " rad: valve.rated_flow_m3ps (flow gain), both chambers' dead volumes (hydraulic stiffness),",
        "internal_leakage_m3ps_per_pa (leakage), actuator.inertia_kgm2 (inertia less the arm model's link),",
        "friction coulomb_nm, static_nm and viscous_nms_per_rad. Everything else as in the starting plant."};
    std::vector<std::string> lines = header;
    for (const std::string& n : r.plant_notes) lines.push_back("Approximate: " + n + ".");
    writeTextFile(out / kIdentifiedPlantFile, plant::formatPlantConfigYaml(identified_plant, model, lines));
    r.plant_written = true;
  } catch (const std::invalid_argument& e) {
    r.plant_note = e.what();
    text << "  no " << kIdentifiedPlantFile << ": " << e.what() << "\n";
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  text << verdictText(r) << "\n";
  for (const std::string& f : r.validation_result.failures) text << "  " << f << "\n";
  if (r.neighbours_held) text << "  note: " << kHeldNeighboursNote << "\n";
  if (!allFinite(r.fit)) text << "  warning: the fit returned a non-finite value or standard error\n";
  return r;
}

}  // namespace

CLI::App* addIdentifyCommand(CLI::App& app, IdentifyOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "identify",
      "Identify one joint's hydraulic parameter groups from closed-loop experiments (on the simulated DTS, the fake "
      "DAQ, the arm or a plant node over LCM, or from recorded logs); write the logs, identified.yaml, summary.json "
      "and report.html");
  OptionDeclarer declare(*cmd, table);
  CLI::Option* io = declare.choice("--io", o.io,
                                   "I/O back-end the experiments run on (sim: the joint alone on the simulated DTS; "
                                   "fakedaq: the comedi back-end on the simulated DTS; comedi: the arm; lcm: a plant "
                                   "node, fullarm plant serve, every joint held)",
                                   {"sim", "fakedaq", "comedi", "lcm"});
  io->capture_default_str();
  declare.name("--joint", o.joint, "Joint to identify (short or model name)")->capture_default_str();
  declare.folder("--out", o.out_dir, "Output folder")->capture_default_str();
  declare.integer(
      "--seed", o.seed,
      "Seed of the simulated sensors' noise, default 1 (sim: the held-out experiment uses seed + 1; not with "
      "comedi or lcm)",
      0, 2147483647);
  declare.file("--daq-config", o.daq_config, "fakedaq, comedi: channel map YAML (default: config/dts_daq.yaml)");
  declare.file("--hil-config", o.hil_config,
               "fakedaq, comedi, lcm: loop configuration YAML: period, latency, safety policy (default: "
               "config/hil.yaml)");
  declare.name("--lcm-url", o.lcm_url,
               std::string("lcm: the plant node's LCM URL (default ") + hil::kDefaultLcmUrl + ": this machine only)");
  declare.number("--duration", o.duration_s, "Excitation time of each experiment", {0.5, 600.0, "s"})
      ->capture_default_str();
  declare.number("--amplitude", o.amplitude_v, "Peak of the excitation on the valve command", {0.01, 5.0, "V"})
      ->capture_default_str();
  declare.number("--hold-angle", o.hold_angle_rad,
                 "The driven joint's hold angle, inside its limits less 0.05 rad and the hold's droop (sim: the "
                 "joint starts there; fakedaq, comedi, lcm: its hold moves it there before the experiments; "
                 "default: the default posture's with sim, where the joint is with a device)",
                 {-kMaxHoldAngleRad, kMaxHoldAngleRad, "rad"});
  declare.flag("--confirm-arm-motion", o.confirm_arm_motion,
               "comedi, or lcm on a node serving the real arm: the workspace is clear for the move to --hold-angle");
  declare.integer("--threads", o.threads, "Threads of the fit's simulations", 1, 64)->capture_default_str();
  declare.file("--start", o.start, "identified.yaml whose model starts the fit (default: the plant joint's groups)");
  declare.file("--plant", o.plant_config,
               "Plant YAML: the simulated DTS of sim and fakedaq, the joints and limits of lcm (the node's "
               "--plant-config), the fit's start and the identified plant's base (default: config/dts_plant.yaml)");
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--settings", o.settings, "Identification settings YAML (default: config/identification.yaml)");
  declare
      .files("--log", o.logs,
             "Recorded experiment logs (CSV or LCM, as identify writes them) to fit instead of running "
             "experiments: all but the last are fitted, the last is held out")
      ->excludes(io);
  declare
      .choice("--log-format", o.log_format,
              "Format of the experiment logs written: csv (a column per signal) or lcm (an LCM log, for "
              "lcm-logplayer and lcm-spy); --log reads either",
              {"csv", "lcm"})
      ->each([&o](const std::string&) { o.log_format_given = true; });
  return cmd;
}

int runIdentify(const IdentifyOptions& o) {
  core::Progress quiet;
  core::Progress& progress = o.progress != nullptr ? *o.progress : quiet;
  const std::filesystem::path out(o.out_dir);
  createOutputFolder(out);
  const Outcome r = identify(o, out, progress, std::cout);
  reports::Report report("identify", "Identification of " + r.joint);
  report.setVerdict(r.validation_result.pass, verdictText(r));
  report.addHeadlineNumber("fit_angle_percent", "Held-out angle fit, simulation", r.validation_result.angle.fit_percent,
                           "%");
  report.addHeadlineNumber("fit_torque_percent", "Held-out torque fit, simulation",
                           r.validation_result.torque.fit_percent, "%");
  report.addHeadlineNumber("prediction_fit_angle_percent", "Held-out angle fit, one step ahead",
                           r.validation_result.angle.prediction_fit_percent, "%");
  report.addHeadlineNumber("wall_time_s", "Wall time", r.wall_s, "s");
  if (r.source != "logs") {
    report.addFile(r.fit_experiments.front().name);
    report.addFile(r.validation.name);
  }
  report.addFile(kIdentifiedFile);
  if (r.plant_written) report.addFile(kIdentifiedPlantFile);
  addToReport(r, report, "Identification");
  writeReport(report, out);
  std::cout << "Identified model: " << (std::filesystem::absolute(out) / kIdentifiedFile).string() << " (" << std::fixed
            << std::setprecision(1) << r.wall_s << " s)\n";
  if (r.plant_written) {
    std::cout << "Identified plant: " << (std::filesystem::absolute(out) / kIdentifiedPlantFile).string() << "\n";
  }
  std::cout << "Report: " << (std::filesystem::absolute(out) / "report.html").string() << "\n";
  return r.validation_result.pass ? kExitPass : kExitFail;
}

IdentifyDemoStep runIdentifyDemoStep(const std::filesystem::path& out_dir, reports::Report& report,
                                     core::Progress& progress) {
  IdentifyOptions o;
  const std::filesystem::path out = out_dir / "identify";
  createOutputFolder(out);
  std::ostringstream text;
  const Outcome r = identify(o, out, progress, text);
  for (const std::string& f : {r.fit_experiments.front().name, r.validation.name, std::string(kIdentifiedFile)}) {
    report.addFile(std::filesystem::path("identify") / f);
  }
  if (r.plant_written) report.addFile(std::filesystem::path("identify") / kIdentifiedPlantFile);
  addToReport(r, report, "Identify a joint");
  IdentifyDemoStep step;
  step.pass = r.validation_result.pass;
  std::ostringstream detail;
  detail << verdictText(r) << ", " << std::fixed << std::setprecision(1) << r.wall_s << " s wall";
  step.detail = detail.str();
  return step;
}

}  // namespace fullarm::app
