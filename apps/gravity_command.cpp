#include "gravity_command.hpp"

#include <atomic>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>
#include <utility>
#include <vector>

#include "cli_values.hpp"
#include "command_device.hpp"
#include "exit_codes.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/core/random.hpp"
#include "fullarm/identification/gravity_yaml.hpp"
#include "fullarm/identification/reference_gravity.hpp"
#include "fullarm/identification/signal_csv.hpp"
#include "fullarm/identification/static_holds.hpp"
#include "fullarm/plant/plant_config.hpp"
#include "output_files.hpp"

namespace fullarm::app {
namespace id = fullarm::identification;

CLI::App* addGravityCommand(CLI::App& app, GravityOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "gravity",
      "Fit the arm's gravity load physically consistent (to the DTS reference's identified torques, to a "
      "static-holds log, or to holds taken on a device with --io) and write it as an arm YAML");
  OptionDeclarer declare(*cmd, table);
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--holds", o.holds,
               "Static-holds log to fit (CSV: time_s, posture_index, side_sign, q_<joint>_rad, tau_<joint>_nm per arm "
               "joint); default: the reference's identified torques");
  CLI::Option* io = declare.choice(
      "--io", o.io,
      "Hold random postures on this device (sim: the simulated DTS; fakedaq: the comedi back-end on it; comedi: the "
      "arm; lcm: a plant node, fullarm plant serve --no-user), write their log holds.csv and fit it",
      {"sim", "fakedaq", "comedi", "lcm"});
  io->excludes(cmd->get_option("--holds"));
  declare.file("--plant", o.plant_config,
               "--io sim, fakedaq: the simulated DTS's plant YAML; lcm: the node's --plant-config, for its joints "
               "(default: config/dts_plant.yaml)");
  declare.file("--sim-arm", o.sim_arm,
               "--io sim, fakedaq: the arm model the simulated DTS moves, the truth of a test (default: --config)");
  declare.file("--daq-config", o.daq_config, "--io fakedaq, comedi: channel map YAML (default: config/dts_daq.yaml)");
  declare.file("--hil-config", o.hil_config,
               "--io: loop configuration YAML: period, latency, safety policy (default: config/hil.yaml)");
  declare.name(
      "--lcm-url", o.lcm_url,
      std::string("--io lcm: the plant node's LCM URL (default ") + hil::kDefaultLcmUrl + ": this machine only)");
  declare.integer("--postures", o.postures,
                  "Random postures: of the fit to the reference (default 400, at least 10) or held on the device "
                  "with --io (default 16)",
                  2, 100000);
  declare.integer("--seed", o.seed, "Seed of the random postures (and of the simulated sensors' noise)", 0, 2147483647)
      ->capture_default_str();
  declare.flag("--confirm-arm-motion", o.confirm_arm_motion,
               "--io comedi, or --io lcm on a node serving the real arm: the arm's workspace is clear; the holds move "
               "every joint at once to random postures "
               "inside the limits less 0.1 rad, with no check for self-collision or the arm's surroundings");
  declare.folder("--out", o.out_dir, "Output folder")->capture_default_str();
  return cmd;
}

namespace {

constexpr double kHoldPeriod_s = 1.0e-3;    // the holds run at the loop's 1 kHz
constexpr int kDefaultDevicePostures = 16;  // --io without --postures
constexpr double kPostureInset_rad = 0.1;   // device postures stay this far inside every limit

std::string readText(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw core::ConfigError(file, "", "cannot be opened");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

std::string fmt(const char* format, double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, format, v);
  return buffer;
}

// The holds log's joints: the arm joints, in model order.
std::vector<int> armIndices(const arm::ArmModel& model) {
  std::vector<int> arm_indices;
  for (int k = 0; k < model.numArmJoints(); ++k) arm_indices.push_back(k);
  return arm_indices;
}

// Fits a holds log (read from `holds_file`): the fitted arm, the printed table and gravity.csv.
arm::ArmModel fitHoldsLog(const arm::ArmModel& nominal, const std::vector<std::string>& names,
                          const std::string& holds_file, std::ostream& out, std::ostringstream& csv) {
  const int n_arm = nominal.numArmJoints();
  std::vector<id::StaticHold> holds;
  try {
    holds = id::readStaticHoldsCsv(holds_file, names);
  } catch (const id::CsvFormatError& e) {
    throw core::ConfigError(holds_file, "", e.what());
  }
  std::vector<id::CombinedHold> combined;
  try {
    combined = id::combineSides(holds);
  } catch (const std::invalid_argument& e) {
    throw core::ConfigError(holds_file, "", e.what());
  }
  const std::vector<int> arm_indices = armIndices(nominal);
  const arm::JointSelection joints(nominal.numJoints(), arm_indices);
  std::vector<Eigen::VectorXd> postures;
  std::vector<Eigen::VectorXd> torques;
  for (const auto& c : combined) {
    postures.push_back(id::holdConfiguration(nominal.defaultPosture(), joints, c.q_rad));
    Eigen::VectorXd tau = Eigen::VectorXd::Zero(nominal.numJoints());
    joints.scatter(c.tau_nm, tau);
    torques.push_back(tau);
  }
  // The log carries the arm joints' torques only: the hand joints are left out, not read as 0 N m.
  const id::GravityFit fit = id::fitConsistentGravityParameters(nominal, postures, torques, {}, arm_indices);
  out << "Gravity fitted to " << combined.size() << " postures held from both sides (" << holds_file << "); "
      << fit.rank << " base parameters\n";
  out << "joint   residual RMS [N m]\n";
  csv << "joint,residual_rms_nm\n";
  for (int k = 0; k < n_arm; ++k) {
    out << names[static_cast<std::size_t>(k)] << "  " << fmt("%.4g", fit.residual_rms_nm[k]) << "\n";
    csv << names[static_cast<std::size_t>(k)] << "," << fmt("%.6g", fit.residual_rms_nm[k]) << "\n";
  }
  return id::withGravityParameters(nominal, fit.parameters);
}

// Why the holds on the real arm need --confirm-arm-motion.
constexpr const char* kRealArmMotion =
    "the holds move the real arm, every joint at once, to random postures inside its limits less 0.1 rad, with no "
    "check for self-collision or the arm's surroundings; clear the workspace, then give --confirm-arm-motion";

// Options that mean nothing with the chosen source are refused, not ignored.
void checkOptionCombination(const GravityOptions& o) {
  const auto refuse = [](const char* option, const std::string& why) { throw core::ConfigError({}, option, why); };
  if (o.io.empty()) {
    for (const auto& [name, value] : {std::pair<const char*, const std::string*>{"--plant", &o.plant_config},
                                      {"--sim-arm", &o.sim_arm},
                                      {"--daq-config", &o.daq_config},
                                      {"--hil-config", &o.hil_config},
                                      {"--lcm-url", &o.lcm_url}}) {
      if (!value->empty()) refuse(name, "is read only when the holds are taken on a device (--io)");
    }
    if (o.confirm_arm_motion) {
      refuse("--confirm-arm-motion", "only --io comedi and --io lcm (a node serving the real arm) move the real arm");
    }
    if (o.holds.empty() && o.postures && *o.postures < 10) {
      refuse("--postures", "the fit to the reference needs at least 10 postures, got " + std::to_string(*o.postures));
    }
    return;
  }
  const hil::IoKind kind = commandIoKind(o.io);
  if ((kind == hil::IoKind::kSim || kind == hil::IoKind::kLcm) && !o.daq_config.empty()) {
    refuse("--daq-config", "only --io fakedaq and --io comedi read a channel map");
  }
  if (kind != hil::IoKind::kLcm && !o.lcm_url.empty()) refuse("--lcm-url", "only --io lcm talks to a plant node");
  if (kind == hil::IoKind::kLcm && !o.sim_arm.empty()) {
    refuse("--sim-arm", "the plant node moves its own arm (fullarm plant serve --config)");
  }
  if (kind != hil::IoKind::kComedi && kind != hil::IoKind::kLcm && o.confirm_arm_motion) {
    refuse("--confirm-arm-motion", "only --io comedi and --io lcm (a node serving the real arm) move the real arm");
  }
  if (kind == hil::IoKind::kComedi) {
    if (!o.confirm_arm_motion) {
      refuse("--confirm-arm-motion", std::string("is required with --io comedi: ") + kRealArmMotion);
    }
    if (!o.plant_config.empty()) refuse("--plant", "the real arm (--io comedi) is no simulated plant");
    if (!o.sim_arm.empty()) refuse("--sim-arm", "the real arm (--io comedi) is no simulated plant");
  }
}

// Random device-order postures: every device joint uniform inside its limits less `inset_rad`.
std::vector<Eigen::VectorXd> randomDevicePostures(const arm::ArmModel& model, const arm::JointSelection& joints,
                                                  int count, double inset_rad, std::uint64_t seed) {
  std::vector<Eigen::VectorXd> out;
  for (int p = 0; p < count; ++p) {
    core::RandomStream rng(seed, 3, static_cast<std::uint64_t>(p));
    Eigen::VectorXd q(joints.size());
    for (int k = 0; k < joints.size(); ++k) {
      const auto& limits = model.joints[static_cast<std::size_t>(joints.modelIndex(k))].limits;
      q[k] = rng.uniform(limits.min_rad + inset_rad, limits.max_rad - inset_rad);
    }
    out.push_back(q);
  }
  return out;
}

// Holds the postures on the device, writes the holds log `file`; returns why the holds stopped
// early (empty when every posture was held from both sides).
std::string takeHolds(const GravityOptions& o, const arm::ArmModel& nominal, const std::vector<std::string>& names,
                      const std::filesystem::path& file) {
  const hil::IoKind kind = commandIoKind(o.io);
  const arm::ArmModel simulated = o.sim_arm.empty() ? nominal : arm::loadArmModel(std::filesystem::path(o.sim_arm));
  const plant::PlantConfig plant_config =
      plant::loadPlantConfig(configPathOr(o.plant_config, plant::defaultPlantConfigPath), simulated);
  const std::unique_ptr<CommandDevice> device =
      openCommandDevice(kind, simulated, plant_config, simulated.defaultPosture(), static_cast<std::uint64_t>(o.seed),
                        o.daq_config, o.hil_config, kHoldPeriod_s, {}, o.lcm_url);
  checkNodeArmMotion(*device, true, o.confirm_arm_motion, "--io lcm on a node serving the real arm", kRealArmMotion);
  hil::IoDevice& io = device->backend->device();
  if (io.joints().modelIndices() != armIndices(nominal)) {
    throw core::ConfigError({}, "--io",
                            "the " + o.io + " device serves other joints than the arm's " +
                                std::to_string(nominal.numArmJoints()) +
                                " (the holds log has a column per arm joint): check the channel map or plant file");
  }
  id::StaticHoldOptions options;
  options.move_s = 1.5;
  options.approach_s = 0.5;
  options.settle_s = 1.0;
  options.average_s = 0.3;
  options.before_read = device->pace;
  for (int k = 0; k < io.joints().size(); ++k) {
    const auto& limits = nominal.joints[static_cast<std::size_t>(io.joints().modelIndex(k))].limits;
    options.min_rad.push_back(limits.min_rad);
    options.max_rad.push_back(limits.max_rad);
  }
  const int count = o.postures.value_or(kDefaultDevicePostures);
  const auto postures =
      randomDevicePostures(nominal, io.joints(), count, kPostureInset_rad, static_cast<std::uint64_t>(o.seed));
  core::Progress& progress = core::progressOrQuiet(o.progress);
  progress.begin("gravity: " + std::to_string(count) + " postures held from both sides on " + o.io,
                 2 * static_cast<std::size_t>(count));
  // The holds run paced by the device, where a write to a blocked terminal would make a read
  // late: the control loop only records each hold, and a reporter thread shows them.
  std::vector<std::pair<int, int>> taken(2 * static_cast<std::size_t>(count));  // (posture, side)
  std::atomic<std::size_t> published{0};
  std::atomic<bool> finished{false};
  options.on_hold = [&](const id::StaticHold& h) {
    const std::size_t k = published.load(std::memory_order_relaxed);
    if (k >= taken.size()) return;
    taken[k] = {h.posture_index, h.side};
    published.store(k + 1, std::memory_order_release);
  };
  std::thread reporter([&] {
    std::size_t shown = 0;
    for (;;) {
      const bool last = finished.load(std::memory_order_acquire);
      const std::size_t n = published.load(std::memory_order_acquire);
      for (; shown < n; ++shown) {
        progress.step("posture " + std::to_string(taken[shown].first + 1) + " of " + std::to_string(count) +
                      (taken[shown].second > 0 ? ", from above" : ", from below"));
      }
      if (last) return;
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
  });
  struct JoinReporter {
    std::atomic<bool>& finished;
    std::thread& thread;
    ~JoinReporter() {
      finished.store(true, std::memory_order_release);
      thread.join();
    }
  };
  id::StaticHoldRun run;
  {
    const JoinReporter join{finished, reporter};
    run = id::runStaticHolds(io, postures, options);
  }
  progress.end(run.completed ? "every posture held from both sides" : "stopped early");
  const std::vector<id::StaticHold>& holds = run.holds;
  const std::string stop_reason = run.stop_reason;
  writeOutput(file, [&] { id::writeStaticHoldsCsv(file, holds, names); });
  return stop_reason;
}

}  // namespace

int runGravity(const GravityOptions& o, std::ostream& out) {
  checkOptionCombination(o);
  const std::filesystem::path arm_file = configPathOr(o.arm_config, arm::defaultArmModelPath);
  const std::string yaml = readText(arm_file);
  const arm::ArmModel nominal = arm::parseArmModel(yaml, arm_file);
  const int n_arm = nominal.numArmJoints();
  std::vector<std::string> names;
  for (int k = 0; k < n_arm; ++k) names.push_back(nominal.joints[static_cast<std::size_t>(k)].name);

  const std::filesystem::path dir(o.out_dir);
  arm::ArmModel fitted;
  std::ostringstream csv;
  std::string note;
  if (!o.io.empty()) {
    createOutputFolder(dir);
    const std::filesystem::path holds_file = dir / "holds.csv";
    const std::string stop_reason = takeHolds(o, nominal, names, holds_file);
    if (!stop_reason.empty()) {
      out << "The holds stopped early, outputs at their safe value (" << stop_reason << "); the holds taken are in "
          << holds_file.string() << ", nothing fitted\n";
      return kExitFail;
    }
    fitted = fitHoldsLog(nominal, names, holds_file.string(), out, csv);
    note = "fitted physically consistent to static holds on " + o.io + " (fullarm gravity --io)";
  } else if (o.holds.empty()) {
    id::ReferenceFitOptions options;
    options.train_postures = o.postures.value_or(400);
    options.heldout_postures = std::max(10, options.train_postures / 2);
    options.seed = static_cast<std::uint64_t>(o.seed);
    const id::ReferenceGravityFit r = id::fitToReferenceGravity(nominal, options);
    fitted = r.fitted;
    note = "fitted physically consistent to the DTS reference's identified gravity torques (fullarm gravity)";
    out << "Gravity fitted to the DTS reference's identified torques (" << options.train_postures << " postures, "
        << options.heldout_postures << " held out)\n";
    out << "joint   held-out RMS fitted / default [N m]   published max fitted / default [N m]   default gain\n";
    csv << "joint,fitted_heldout_rms_nm,default_heldout_rms_nm,fitted_published_max_nm,default_published_max_nm,"
           "fitted_gain,default_gain\n";
    for (std::size_t k = 0; k < r.joints.size(); ++k) {
      const auto e = static_cast<Eigen::Index>(k);
      out << r.joints[k] << (r.joints[k].size() < 6 ? std::string(6 - r.joints[k].size(), ' ') : "") << "  "
          << fmt("%.2e", r.fitted_vs_reference.heldout_rms_nm[e]) << " / "
          << fmt("%.3f", r.nominal_vs_reference.heldout_rms_nm[e]) << "            "
          << fmt("%.2e", r.fitted_vs_reference.published_max_nm[e]) << " / "
          << fmt("%.3f", r.nominal_vs_reference.published_max_nm[e]) << "              "
          << fmt("%.3f", r.nominal_vs_reference.gain[e]) << "\n";
      csv << r.joints[k] << "," << fmt("%.6g", r.fitted_vs_reference.heldout_rms_nm[e]) << ","
          << fmt("%.6g", r.nominal_vs_reference.heldout_rms_nm[e]) << ","
          << fmt("%.6g", r.fitted_vs_reference.published_max_nm[e]) << ","
          << fmt("%.6g", r.nominal_vs_reference.published_max_nm[e]) << ","
          << fmt("%.6g", r.fitted_vs_reference.gain[e]) << "," << fmt("%.6g", r.nominal_vs_reference.gain[e]) << "\n";
    }
  } else {
    fitted = fitHoldsLog(nominal, names, o.holds, out, csv);
    note = "fitted physically consistent to static holds (fullarm gravity --holds)";
  }
  createOutputFolder(dir);
  writeTextFile(dir / "arm.yaml", id::armYamlWithGravity(yaml, arm_file.string(), nominal, fitted, note));
  writeTextFile(dir / "gravity.csv", csv.str());
  out << "Wrote " << (dir / "arm.yaml").string() << " and " << (dir / "gravity.csv").string() << "\n";
  return kExitPass;
}

}  // namespace fullarm::app
