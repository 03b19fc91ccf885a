#include "gravity_command.hpp"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "cli_values.hpp"
#include "exit_codes.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/identification/gravity_yaml.hpp"
#include "fullarm/identification/reference_gravity.hpp"
#include "fullarm/identification/signal_csv.hpp"
#include "fullarm/identification/static_holds.hpp"
#include "output_files.hpp"

namespace fullarm::app {
namespace id = fullarm::identification;

CLI::App* addGravityCommand(CLI::App& app, GravityOptions& o, OptionTable& table) {
  CLI::App* cmd = app.add_subcommand(
      "gravity",
      "Fit the arm's gravity load physically consistent (to the DTS reference's identified torques, or to a "
      "static-holds log) and write it as an arm YAML");
  OptionDeclarer declare(*cmd, table);
  declare.file("--config", o.arm_config, "Arm model YAML (default: config/dts_master.yaml)");
  declare.file("--holds", o.holds,
               "Static-holds log to fit (CSV: time_s, posture_index, side_sign, q_<joint>_rad, tau_<joint>_nm per arm "
               "joint); default: the reference's identified torques");
  declare.integer("--postures", o.postures, "Random postures of the fit to the reference", 10, 100000)
      ->capture_default_str();
  declare.integer("--seed", o.seed, "Seed of the random postures", 0, 2147483647)->capture_default_str();
  declare.folder("--out", o.out_dir, "Output folder")->capture_default_str();
  return cmd;
}

namespace {

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

}  // namespace

int runGravity(const GravityOptions& o, std::ostream& out) {
  const std::filesystem::path arm_file = configPathOr(o.arm_config, arm::defaultArmModelPath);
  const std::string yaml = readText(arm_file);
  const arm::ArmModel nominal = arm::parseArmModel(yaml, arm_file);
  const int n_arm = nominal.numArmJoints();
  std::vector<std::string> names;
  for (int k = 0; k < n_arm; ++k) names.push_back(nominal.joints[static_cast<std::size_t>(k)].name);

  arm::ArmModel fitted;
  std::ostringstream csv;
  std::string note;
  if (o.holds.empty()) {
    id::ReferenceFitOptions options;
    options.train_postures = o.postures;
    options.heldout_postures = std::max(10, o.postures / 2);
    options.seed = static_cast<std::uint64_t>(o.seed);
    const id::ReferenceGravityFit r = id::fitToReferenceGravity(nominal, options);
    fitted = r.fitted;
    note = "fitted physically consistent to the DTS reference's identified gravity torques (fullarm gravity)";
    out << "Gravity fitted to the DTS reference's identified torques (" << o.postures << " postures, "
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
    std::vector<id::StaticHold> holds;
    try {
      holds = id::readStaticHoldsCsv(o.holds, names);
    } catch (const id::CsvFormatError& e) {
      throw core::ConfigError(o.holds, "", e.what());
    }
    std::vector<id::CombinedHold> combined;
    try {
      combined = id::combineSides(holds);
    } catch (const std::invalid_argument& e) {
      throw core::ConfigError(o.holds, "", e.what());
    }
    std::vector<int> arm_indices;
    for (int k = 0; k < n_arm; ++k) arm_indices.push_back(k);
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
    fitted = id::withGravityParameters(nominal, fit.parameters);
    note = "fitted physically consistent to static holds (fullarm gravity --holds)";
    out << "Gravity fitted to " << combined.size() << " postures held from both sides (" << o.holds << "); " << fit.rank
        << " base parameters\n";
    out << "joint   residual RMS [N m]\n";
    csv << "joint,residual_rms_nm\n";
    for (int k = 0; k < n_arm; ++k) {
      out << names[static_cast<std::size_t>(k)] << "  " << fmt("%.4g", fit.residual_rms_nm[k]) << "\n";
      csv << names[static_cast<std::size_t>(k)] << "," << fmt("%.6g", fit.residual_rms_nm[k]) << "\n";
    }
  }
  const std::filesystem::path dir(o.out_dir);
  createOutputFolder(dir);
  writeTextFile(dir / "arm.yaml", id::armYamlWithGravity(yaml, arm_file.string(), nominal, fitted, note));
  writeTextFile(dir / "gravity.csv", csv.str());
  out << "Wrote " << (dir / "arm.yaml").string() << " and " << (dir / "gravity.csv").string() << "\n";
  return kExitPass;
}

}  // namespace fullarm::app
