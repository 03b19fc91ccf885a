// `fullarm identify` end to end: a short run on the simulated DTS writes its logs, identified.yaml
// (which the library reads back), identified_plant.yaml (a plant whose elbow has the identified
// groups), summary.json and report.html with finite parameters inside their bounds and the
// one-step prediction fit beside the simulation's; fitting the written logs again with --log
// gives the same parameters; bad input exits 2 with a message naming the option, file or line.

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "arm_test_util.hpp"
#include "cli_runner.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/identification/experiment_lcm.hpp"
#include "fullarm/identification/identified_model.hpp"
#include "fullarm/identification/joint_groups.hpp"
#include "fullarm/identification/signal_csv.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace {

using Result = fullarm::test::CliResult;
// The fake DAQ's groups against the plant's: 10 %, as on --io sim (the same simulated joint,
// here read and driven through the channel map's converters and calibrations).
constexpr double kFakeDaqTolerance = 0.10;
using fullarm::test::runFullarm;
namespace id = fullarm::identification;

std::filesystem::path tempDir(const std::string& name) {
  return fullarm::test::cliTempDir("fullarm_identify_cli_test", name);
}

nlohmann::json readSummary(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

TEST(IdentifyCli, SimRunWritesItsFilesAndLogRunRefitsTheSameParameters) {
  const auto dir = tempDir("sim");
  const Result r = runFullarm("identify --io sim --joint EB --duration 1 --quiet --out " + dir.string());
  // On the simulated plant the model fits the held-out data but its residuals are not white
  // (docs/identification.md): 1 (fails) is expected, 0 allowed; anything else is an error.
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  for (const char* f :
       {"experiment_fit.csv", "experiment_validation.csv", "identified.yaml", "summary.json", "report.html"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  }
  const nlohmann::json summary = readSummary(dir);
  const nlohmann::json& result = summary["results"]["identify"];
  EXPECT_EQ(result["joint"], "R_EB");
  const id::IdentifiedModel identified = id::loadIdentifiedModel(dir / "identified.yaml");
  EXPECT_EQ(identified.joint, "R_EB");
  for (int i = 0; i < id::kGreyParams; ++i) {
    const char* name = id::greyParamName(i);
    const nlohmann::json& p = result["parameters"][name];
    const double value = p["value"].get<double>();
    const double se = p["standard_error"].get<double>();
    EXPECT_TRUE(std::isfinite(value)) << name;
    EXPECT_TRUE(std::isfinite(se) && se >= 0.0) << name;
    EXPECT_GE(value, p["min"].get<double>()) << name;
    EXPECT_LE(value, p["max"].get<double>()) << name;
    // identified.yaml holds the same numbers as the summary.
    EXPECT_EQ(identified.model.value[static_cast<std::size_t>(i)], value) << name;
    EXPECT_EQ(identified.standard_error[static_cast<std::size_t>(i)], se) << name;
  }
  const double fit_angle = result["validation"]["fit_angle_percent"].get<double>();
  EXPECT_TRUE(std::isfinite(fit_angle));
  // The driven joint alone and the valve's structure in the model: the held-out fit reaches 90 %
  // in both channels even from 1 s experiments, the delay is the simulated DTS's one-sample
  // latency, and the flow gain, hydraulic stiffness and inertia lie within 10 % of the plant's
  // groups the fit started from.
  EXPECT_GE(fit_angle, 90.0);
  EXPECT_GE(result["validation"]["fit_torque_percent"].get<double>(), 90.0);
  EXPECT_EQ(result["delay_samples"].get<int>(), 1);
  for (const char* name : {"flow_gain_radps_per_v", "hydraulic_stiffness_nm_per_rad", "inertia_kgm2"}) {
    const double plant = result["parameters"][name]["start"].get<double>();
    EXPECT_NEAR(result["parameters"][name]["value"].get<double>(), plant, 0.10 * plant) << name;
  }
  EXPECT_EQ(result["validation"]["pass"].get<bool>(), r.exit_code == 0);
  // The one-step-ahead prediction is reported beside the simulation (its fit, not the
  // simulation's, depends on the filter's noise levels: no ordering between the two is asserted).
  EXPECT_GE(result["validation"]["prediction_fit_angle_percent"].get<double>(), 90.0);
  EXPECT_GE(result["validation"]["prediction_fit_torque_percent"].get<double>(), 90.0);
  EXPECT_NE(r.output.find("one-step prediction fit"), std::string::npos) << r.output;
  // The report names the source and tabulates the fitted experiment's estimated initial state.
  {
    std::ifstream in(dir / "report.html");
    std::stringstream html;
    html << in.rdbuf();
    EXPECT_NE(html.str().find("on the simulated DTS (the joint alone"), std::string::npos);
    EXPECT_NE(html.str().find("Initial state of each fitted experiment"), std::string::npos);
    EXPECT_NE(html.str().find("every other joint at the arm"), std::string::npos);
    // The initial-state table's row holds the summary's estimates, to the table's four digits.
    const nlohmann::json& x0 = result["experiments"][0]["initial_state"];
    const auto cell = [](double v) {
      char text[64];
      std::snprintf(text, sizeof text, "<td class=\"num\">%.4g</td>", v);
      return std::string(text);
    };
    const std::string row = "<tr><td>experiment_fit.csv</td>" + cell(x0["speed_radps"].get<double>()) +
                            cell(x0["speed_standard_error"].get<double>()) +
                            cell(x0["torque_offset_nm"].get<double>()) +
                            cell(x0["torque_offset_standard_error"].get<double>()) + "</tr>";
    EXPECT_NE(html.str().find(row), std::string::npos) << row;
  }

  // The start's link inertia and gravity load are KDL's at the arm's default posture with the
  // elbow at its hold angle (the other joints are locked there; the log names no held joint).
  EXPECT_TRUE(result["experiments"][0]["held_joints_rad"].empty()) << result["experiments"][0].dump();
  {
    const fullarm::arm::ArmModel arm = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
    Eigen::VectorXd q = arm.defaultPosture();
    const int elbow = arm.jointIndex("R_EB");
    q[elbow] = result["experiments"][0]["hold_rad"].get<double>();
    const fullarm::arm::test::KdlJointAtRest kdl = fullarm::arm::test::kdlJointAtRest(arm, q, elbow);
    EXPECT_NEAR(result["start_gravity_load_nm"].get<double>(), kdl.gravity_nm, 1e-9 * std::abs(kdl.gravity_nm));
    EXPECT_NEAR(result["start_link_inertia_kgm2"].get<double>(), kdl.inertia_kgm2, 1e-9 * kdl.inertia_kgm2);
  }

  // The identified plant file: a plant YAML whose elbow has the identified groups at the hold
  // angle (the inertia is the link's share plus the actuator's, checked in identified_plant_test),
  // the other joints the shipped ones.
  ASSERT_EQ(result["identified_plant"], "identified_plant.yaml") << result["identified_plant_refused"];
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  const fullarm::plant::PlantConfig shipped =
      fullarm::plant::loadPlantConfig(fullarm::plant::defaultPlantConfigPath(), model);
  const fullarm::plant::PlantConfig written = fullarm::plant::loadPlantConfig(dir / "identified_plant.yaml", model);
  const int eb = fullarm::plant::findPlantJoint(written, "EB");
  const double q_hold = result["experiments"][0]["hold_rad"].get<double>();
  const id::GreyModel own = id::greyModelFromJoint(written.joints[static_cast<std::size_t>(eb)], q_hold, 0.0, 0.0, 1);
  for (const int i : {id::kFlowGain, id::kStiffness, id::kLeakage, id::kViscous, id::kCoulomb}) {
    const double want = identified.model.value[static_cast<std::size_t>(i)];
    EXPECT_NEAR(own.value[static_cast<std::size_t>(i)], want, 1e-9 * want) << id::greyParamName(i);
  }
  for (std::size_t k = 0; k < written.joints.size(); ++k) {
    if (static_cast<int>(k) == eb) continue;
    EXPECT_EQ(written.joints[k].valve.rated_flow_m3ps, shipped.joints[k].valve.rated_flow_m3ps);
    EXPECT_EQ(written.joints[k].chambers.dead_volume_a_m3, shipped.joints[k].chambers.dead_volume_a_m3);
  }

  // The same data through --log: the same fit.
  const auto again = tempDir("log");
  const Result l = runFullarm("identify --quiet --joint EB --log " + (dir / "experiment_fit.csv").string() + " " +
                              (dir / "experiment_validation.csv").string() + " --out " + again.string());
  ASSERT_EQ(l.exit_code, r.exit_code) << l.output;
  const id::IdentifiedModel refit = id::loadIdentifiedModel(again / "identified.yaml");
  EXPECT_EQ(refit.model.delay_samples, identified.model.delay_samples);
  for (int i = 0; i < id::kGreyParams; ++i) {
    EXPECT_EQ(refit.model.value[static_cast<std::size_t>(i)], identified.model.value[static_cast<std::size_t>(i)])
        << id::greyParamName(i);
    EXPECT_EQ(refit.standard_error[static_cast<std::size_t>(i)], identified.standard_error[static_cast<std::size_t>(i)])
        << id::greyParamName(i);
  }
  EXPECT_EQ(readSummary(again)["results"]["identify"]["validation"]["fit_angle_percent"].get<double>(), fit_angle);

  // The identified model starts another fit.
  const auto restart = tempDir("start");
  const Result s = runFullarm("identify --quiet --log " + (dir / "experiment_fit.csv").string() + " " +
                              (dir / "experiment_validation.csv").string() + " --start " +
                              (dir / "identified.yaml").string() + " --out " + restart.string());
  EXPECT_TRUE(s.exit_code == 0 || s.exit_code == 1) << s.output;
  EXPECT_EQ(readSummary(restart)["results"]["identify"]["start"], (dir / "identified.yaml").string());
}

// The logs written as LCM logs (--log-format lcm) fit again through --log to the same parameters
// as the run itself; a log of another joint, and --log-format beside --log, are exit 2.
TEST(IdentifyCli, LcmLogsAreWrittenAndRefitToTheSameParameters) {
  const auto dir = tempDir("lcm_logs");
  const Result r =
      runFullarm("identify --io sim --joint EB --duration 1 --log-format lcm --quiet --out " + dir.string());
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  const auto fit_log = dir / "experiment_fit.lcm";
  const auto validation_log = dir / "experiment_validation.lcm";
  ASSERT_TRUE(std::filesystem::exists(fit_log));
  ASSERT_TRUE(std::filesystem::exists(validation_log));
  EXPECT_FALSE(std::filesystem::exists(dir / "experiment_fit.csv"));
  const nlohmann::json summary = readSummary(dir);
  EXPECT_EQ(summary["results"]["identify"]["experiments"][0]["file"], "experiment_fit.lcm");
  // The log says what wrote it.
  const id::ExperimentLcmLog recorded = id::readExperimentLcmLog(fit_log);
  EXPECT_EQ(recorded.info.joint, "R_EB");
  EXPECT_EQ(recorded.info.source, "sim");
  EXPECT_NE(recorded.info.command_line.find("--log-format lcm"), std::string::npos) << recorded.info.command_line;
  EXPECT_EQ(recorded.table.rows(), 1000u);

  const auto again = tempDir("lcm_refit");
  const Result l = runFullarm("identify --quiet --joint EB --log " + fit_log.string() + " " + validation_log.string() +
                              " --out " + again.string());
  ASSERT_EQ(l.exit_code, r.exit_code) << l.output;
  const id::IdentifiedModel first = id::loadIdentifiedModel(dir / "identified.yaml");
  const id::IdentifiedModel refit = id::loadIdentifiedModel(again / "identified.yaml");
  for (int i = 0; i < id::kGreyParams; ++i) {
    EXPECT_EQ(refit.model.value[static_cast<std::size_t>(i)], first.model.value[static_cast<std::size_t>(i)])
        << id::greyParamName(i);
  }

  const Result other = runFullarm("identify --quiet --joint SFE --log " + fit_log.string() + " " +
                                  validation_log.string() + " --out " + again.string());
  EXPECT_EQ(other.exit_code, 2) << other.output;
  EXPECT_NE(other.output.find(fit_log.string()), std::string::npos) << other.output;
  EXPECT_NE(other.output.find("drove R_EB"), std::string::npos) << other.output;
  const Result format = runFullarm("identify --quiet --log-format csv --log " + fit_log.string() + " " +
                                   validation_log.string() + " --out " + again.string());
  EXPECT_EQ(format.exit_code, 2) << format.output;
  EXPECT_NE(format.output.find("--log-format"), std::string::npos) << format.output;
  const Result bad_format = runFullarm("identify --quiet --log-format hdf5 --out " + again.string());
  EXPECT_EQ(bad_format.exit_code, 2) << bad_format.output;
  EXPECT_NE(bad_format.output.find("--log-format"), std::string::npos) << bad_format.output;

  // A damaged LCM log: exit 2 naming the file and the byte offset.
  const auto damaged = dir / "damaged.lcm";
  std::filesystem::copy_file(fit_log, damaged);
  {
    std::fstream f(damaged, std::ios::in | std::ios::out | std::ios::binary);
    f.seekp(400);
    const char junk[8] = {'\x7f', '\x7f', '\x7f', '\x7f', '\x7f', '\x7f', '\x7f', '\x7f'};
    f.write(junk, sizeof junk);
  }
  const Result d = runFullarm("identify --quiet --joint EB --log " + damaged.string() + " " + validation_log.string() +
                              " --out " + again.string());
  EXPECT_EQ(d.exit_code, 2) << d.output;
  EXPECT_NE(d.output.find(damaged.string()), std::string::npos) << d.output;
  EXPECT_NE(d.output.find("byte offset"), std::string::npos) << d.output;
}

// A plant file whose elbow has chamber pressure transducers (0-25 MPa, 12 bits) with the given
// noise; `sensor_noise` false takes the elbow's potentiometer and load-cell noise away too.
std::filesystem::path plantWithPressures(const std::filesystem::path& dir, double pressure_noise_pa,
                                         bool sensor_noise) {
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  fullarm::plant::PlantConfig config = fullarm::plant::loadPlantConfig(fullarm::plant::defaultPlantConfigPath(), model);
  fullarm::plant::JointParams& eb =
      config.joints[static_cast<std::size_t>(fullarm::plant::findPlantJoint(config, "EB"))];
  eb.sensor_noise.pressure_full_scale_pa = 25.0e6;
  eb.sensor_noise.pressure_bits = 12;
  eb.sensor_noise.pressure_noise_pa = pressure_noise_pa;
  if (!sensor_noise) {
    eb.sensor_noise.angle_noise_rad = 0.0;
    eb.sensor_noise.torque_noise_nm = 0.0;
  }
  std::filesystem::create_directories(dir);
  const auto file = dir / "plant_with_pressures.yaml";
  std::ofstream(file) << fullarm::plant::formatPlantConfigYaml(config, model, {"the elbow with pressure transducers"});
  return file;
}

// With the chamber pressures logged the friction shows directly, as the gap between the hydraulic
// torque and the load cell: on the simulated elbow (fullarm identify's default run, two 5 s
// experiments) without sensor noise every group lies within 2 % of the plant's own and the delay
// is exact; with the sensors' noise (10 kPa on the pressures) within 10 %, viscous friction
// included. The logs carry the pressures, in CSV and in LCM, and the LCM logs refit to the same
// parameters.
// With the chamber pressures logged the friction shows directly, as the gap between the hydraulic
// torque and the load cell: on the simulated elbow (fullarm identify's default run, two 5 s
// experiments) without sensor noise every group lies within 2 % of the plant's own and the delay
// is exact; with the sensors' noise (10 kPa on the pressures), started from a model off the plant's
// by factors of 2 (--start), within 10 %, viscous friction included. The logs carry the pressures,
// in CSV and in LCM, and the LCM logs refit to the same parameters.
TEST(IdentifyCli, ChamberPressuresPinTheFrictionOnTheSimulatedJoint) {
  const std::vector<std::string> groups{"flow_gain_radps_per_v", "hydraulic_stiffness_nm_per_rad",
                                        "leakage_radps_per_nm",  "inertia_kgm2",
                                        "viscous_nms_per_rad",   "coulomb_nm",
                                        "load_torque_nm"};
  const auto clean = tempDir("pressures_noise_free");
  const Result r = runFullarm("identify --io sim --joint EB --quiet --plant " +
                              plantWithPressures(clean, 0.0, false).string() + " --out " + clean.string());
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  // Without --start the fit starts from the plant's groups at the hold angle: the truth here.
  const nlohmann::json truth = readSummary(clean)["results"]["identify"]["parameters"];
  const auto expectGroups = [&](const nlohmann::json& result, double tolerance) {
    for (const std::string& name : groups) {
      const double plant = truth[name]["start"].get<double>();
      EXPECT_NEAR(result["parameters"][name]["value"].get<double>(), plant, tolerance * plant) << name;
    }
    EXPECT_EQ(result["delay_samples"].get<int>(), 1);
    EXPECT_GE(result["validation"]["fit_hydraulic_torque_percent"].get<double>(), 90.0);
  };
  {
    SCOPED_TRACE("noise-free");
    expectGroups(readSummary(clean)["results"]["identify"], 0.02);
  }
  {
    std::ifstream in(clean / "experiment_fit.csv");
    std::string header;
    std::getline(in, header);
    EXPECT_EQ(header.rfind("time_s,excitation_v,command_v,q_rad,tau_measured_nm,pressure_a_pa,pressure_b_pa", 0), 0u)
        << header;
    std::ifstream html_in(clean / "report.html");
    std::stringstream html;
    html << html_in.rdbuf();
    EXPECT_NE(html.str().find("hydraulic torque from the chamber pressures"), std::string::npos);
  }
  EXPECT_NE(r.output.find("hydraulic torque from the chamber pressures"), std::string::npos) << r.output;

  // A start off the plant's groups by factors of 2 either way (from the noise-free fit, within
  // 2 % of them).
  const auto noisy = tempDir("pressures_noisy");
  id::IdentifiedModel start = id::loadIdentifiedModel(clean / "identified.yaml");
  const std::array<double, 6> factor{2.0, 0.5, 2.0, 0.5, 2.0, 0.5};
  int c = 0;
  for (const int i : {id::kFlowGain, id::kStiffness, id::kLeakage, id::kInertia, id::kViscous, id::kCoulomb}) {
    start.model.value[static_cast<std::size_t>(i)] *= factor[static_cast<std::size_t>(c++)];
  }
  const auto start_file = noisy / "start.yaml";
  std::ofstream(start_file) << id::formatIdentifiedModelYaml(start);
  const Result n = runFullarm("identify --io sim --joint EB --quiet --log-format lcm --plant " +
                              plantWithPressures(noisy, 1.0e4, true).string() + " --start " + start_file.string() +
                              " --out " + noisy.string());
  ASSERT_TRUE(n.exit_code == 0 || n.exit_code == 1) << n.output;
  {
    SCOPED_TRACE("with the sensors' noise, from the start off the plant");
    const nlohmann::json result = readSummary(noisy)["results"]["identify"];
    EXPECT_EQ(result["parameters"]["viscous_nms_per_rad"]["start"].get<double>(), start.model.value[id::kViscous]);
    expectGroups(result, 0.10);
  }
  const id::ExperimentLcmLog recorded = id::readExperimentLcmLog(noisy / "experiment_fit.lcm");
  EXPECT_TRUE(recorded.table.has("pressure_a_pa") && recorded.table.has("pressure_b_pa"));
  const auto again = tempDir("pressures_refit");
  const Result l = runFullarm("identify --quiet --joint EB --log " + (noisy / "experiment_fit.lcm").string() + " " +
                              (noisy / "experiment_validation.lcm").string() + " --start " + start_file.string() +
                              " --out " + again.string());
  ASSERT_EQ(l.exit_code, n.exit_code) << l.output;
  const id::IdentifiedModel first = id::loadIdentifiedModel(noisy / "identified.yaml");
  const id::IdentifiedModel refit = id::loadIdentifiedModel(again / "identified.yaml");
  for (int i = 0; i < id::kGreyParams; ++i) {
    EXPECT_EQ(refit.model.value[static_cast<std::size_t>(i)], first.model.value[static_cast<std::size_t>(i)])
        << id::greyParamName(i);
  }
}

TEST(IdentifyCli, BadInputExitsTwoNamingTheOptionFileOrLine) {
  const auto dir = tempDir("bad");
  const auto expectBad = [&](const std::string& args, const std::string& named) {
    const Result r = runFullarm("identify --quiet --out " + dir.string() + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(named), std::string::npos) << args << ": expected '" << named << "' in\n" << r.output;
  };
  expectBad("--joint XX", "--joint");
  expectBad("--duration nan", "--duration");
  expectBad("--duration=-1", "--duration");
  expectBad("--duration 0", "--duration");
  expectBad("--hold-angle nan", "--hold-angle");
  expectBad("--hold-angle inf", "--hold-angle");
  expectBad("--hold-angle 7", "--hold-angle");
  // Outside the elbow's limits less the margin: the range it must be in.
  expectBad("--joint EB --hold-angle 0.3", "--hold-angle: 0.3 rad is outside R_EB's limits");
  expectBad("--joint EB --hold-angle 2.2", "expected 0.636132..2.1589 rad");
  const std::string missing = (dir / "missing.csv").string();
  expectBad("--log " + missing + " " + missing, "--log");

  // A malformed log: a field that is not a number on line 3.
  const auto bad_log = dir / "malformed.csv";
  {
    std::ofstream out(bad_log);
    out << "time_s,excitation_v,command_v,q_rad,tau_measured_nm\n"
        << "0,0,0,1.2,0\n"
        << "0.001,0.1,zero,1.2,0\n";
  }
  const Result m =
      runFullarm("identify --quiet --out " + dir.string() + " --log " + bad_log.string() + " " + bad_log.string());
  EXPECT_EQ(m.exit_code, 2) << m.output;
  EXPECT_NE(m.output.find(bad_log.string()), std::string::npos) << m.output;
  EXPECT_NE(m.output.find("3"), std::string::npos) << m.output;
  EXPECT_NE(m.output.find("zero"), std::string::npos) << m.output;

  // A held joint's column naming no joint of the arm, or the identified joint itself: exit 2
  // naming the file and the column.
  for (const std::string column : {"held_XX_rad", "held_R_EB_rad"}) {
    const auto held_log = dir / "held.csv";
    {
      std::ofstream out(held_log);
      out << "time_s,excitation_v,command_v,q_rad,tau_measured_nm," << column << "\n"
          << "0,0,0,1.2,0,0.1\n"
          << "0.001,0.1,0.1,1.2,0,0.1\n"
          << "0.002,0.1,0.1,1.21,0,0.1\n";
    }
    const Result h = runFullarm("identify --quiet --joint EB --out " + dir.string() + " --log " + held_log.string() +
                                " " + held_log.string());
    EXPECT_EQ(h.exit_code, 2) << h.output;
    EXPECT_NE(h.output.find(held_log.string()), std::string::npos) << h.output;
    EXPECT_NE(h.output.find(column), std::string::npos) << h.output;
  }

  // A log too short to fit: exit 2 naming the file.
  const auto short_log = dir / "short.csv";
  {
    std::ofstream out(short_log);
    out << "time_s,excitation_v,command_v,q_rad,tau_measured_nm\n";
    for (int k = 0; k < 5; ++k) out << 0.001 * k << ",0.1," << 0.1 - 0.01 * k << "," << 1.2 + 0.001 * k << ",0\n";
  }
  const Result s = runFullarm("identify --quiet --joint EB --out " + dir.string() + " --log " + short_log.string() +
                              " " + short_log.string());
  EXPECT_EQ(s.exit_code, 2) << s.output;
  EXPECT_NE(s.output.find(short_log.string()), std::string::npos) << s.output;
  EXPECT_NE(s.output.find("expected at least 64"), std::string::npos) << s.output;

  // One chamber's pressure without the other's: exit 2 naming the file and the missing column.
  const auto one_pressure = dir / "one_pressure.csv";
  {
    std::ofstream out(one_pressure);
    out << "time_s,excitation_v,command_v,q_rad,tau_measured_nm,pressure_a_pa\n";
    for (int k = 0; k < 100; ++k) {
      const double r = k % 2 == 0 ? 0.1 : -0.1;
      const double q = 1.2 + 0.001 * std::sin(0.3 * k);
      out << 0.001 * k << "," << r << "," << 10.0 * (1.2 - q) + r << "," << q << ",10," << 1.0e7 + 1.0e4 * k << "\n";
    }
  }
  const Result p = runFullarm("identify --quiet --joint EB --out " + dir.string() + " --log " + one_pressure.string() +
                              " " + one_pressure.string());
  EXPECT_EQ(p.exit_code, 2) << p.output;
  EXPECT_NE(p.output.find(one_pressure.string()), std::string::npos) << p.output;
  EXPECT_NE(p.output.find("no column pressure_b_pa"), std::string::npos) << p.output;

  // Only one log: nothing to hold out.
  const Result one = runFullarm("identify --quiet --out " + dir.string() + " --log " + bad_log.string());
  EXPECT_EQ(one.exit_code, 2) << one.output;
  EXPECT_NE(one.output.find("--log"), std::string::npos) << one.output;
}

// The same identification through the fake DAQ: the comedi back-end's code on the simulated DTS
// with the channel map's 12-bit inputs and 16-bit outputs (the simulated DTS locks the other
// joints, as with --io sim). The groups the experiments show are the plant's own at the hold
// angle (greyModelFromJoint, the fit's start), and the delay is the loop's one-sample latency.
TEST(IdentifyCli, FakeDaqRunIdentifiesThePlantsOwnGroups) {
  const auto dir = tempDir("fakedaq");
  const Result r = runFullarm("identify --io fakedaq --joint EB --duration 1 --quiet --out " + dir.string());
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  for (const char* f :
       {"experiment_fit.csv", "experiment_validation.csv", "identified.yaml", "summary.json", "report.html"}) {
    EXPECT_TRUE(std::filesystem::exists(dir / f)) << f;
  }
  const nlohmann::json result = readSummary(dir)["results"]["identify"];
  EXPECT_EQ(result["source"], "fakedaq");
  // The simulated DTS locks the neighbours: no coupling to warn of.
  EXPECT_FALSE(result["neighbours_held"].get<bool>());
  EXPECT_EQ(r.output.find("held, not locked"), std::string::npos) << r.output;
  EXPECT_TRUE(result["experiments"][0]["completed"].get<bool>());
  EXPECT_TRUE(result["experiments"][1]["completed"].get<bool>());
  std::printf("fakedaq: delay %d samples, fit angle %.1f %%, torque %.1f %%\n", result["delay_samples"].get<int>(),
              result["validation"]["fit_angle_percent"].get<double>(),
              result["validation"]["fit_torque_percent"].get<double>());
  // The start is the plant's own groups: recompute them independently from the plant file.
  const fullarm::arm::ArmModel model = fullarm::arm::loadArmModel(fullarm::arm::defaultArmModelPath());
  const fullarm::plant::PlantConfig plant =
      fullarm::plant::loadPlantConfig(fullarm::plant::defaultPlantConfigPath(), model);
  const int eb = fullarm::plant::findPlantJoint(plant, "EB");
  const double q_hold = result["experiments"][0]["hold_rad"].get<double>();
  const id::GreyModel own = id::greyModelFromJoint(plant.joints[static_cast<std::size_t>(eb)], q_hold, 0.0, 0.0, 1);
  for (const int i : {id::kFlowGain, id::kStiffness}) {
    const char* name = id::greyParamName(i);
    EXPECT_NEAR(result["parameters"][name]["start"].get<double>(), own.value[static_cast<std::size_t>(i)],
                1e-9 * own.value[static_cast<std::size_t>(i)])
        << name;
  }
  for (const char* name : {"flow_gain_radps_per_v", "hydraulic_stiffness_nm_per_rad", "inertia_kgm2"}) {
    const double plant_value = result["parameters"][name]["start"].get<double>();
    const double value = result["parameters"][name]["value"].get<double>();
    std::printf("%s: plant %.6g, identified %.6g (%+.1f %%)\n", name, plant_value, value,
                100.0 * (value / plant_value - 1.0));
    EXPECT_NEAR(value, plant_value, kFakeDaqTolerance * plant_value) << name;
  }
  EXPECT_EQ(result["delay_samples"].get<int>(), 1);
  EXPECT_GE(result["validation"]["fit_angle_percent"].get<double>(), 90.0);
  // The held-out experiment holds the elbow where the fitted one did, not where the PRBS left it:
  // the hold law recovered from each log has the same target.
  const double fitted_hold = result["experiments"][0]["hold_rad"].get<double>();
  const double held_out_hold = result["experiments"][1]["hold_rad"].get<double>();
  std::printf("hold angles: fitted %.7f rad, held out %.7f rad\n", fitted_hold, held_out_hold);
  EXPECT_NEAR(held_out_hold, fitted_hold, 1e-6);
}

// An experiment that stops early keeps its log: a 5 V PRBS on the elbow held 0.02 rad short of its
// upper limit's margin drives it into the margin within a few dozen samples, too few to fit
// (exit 2), and the samples it ran are on disk.
TEST(IdentifyCli, AnExperimentThatStopsEarlyKeepsWhatItLogged) {
  const auto dir = tempDir("stopped");
  const Result r = runFullarm(
      "identify --quiet --io sim --joint EB --duration 1 --amplitude 5 --hold-angle 2.14 --out " + dir.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  const std::string marker = "the experiment logging to experiment_fit.csv stopped after ";
  const std::size_t at = r.output.find(marker);
  ASSERT_NE(at, std::string::npos) << r.output;
  const std::size_t rows = std::stoul(r.output.substr(at + marker.size()));
  ASSERT_GT(rows, 0U) << r.output;
  const id::SignalTable kept = id::readSignalCsv(dir / "experiment_fit.csv", id::kExperimentColumns);
  EXPECT_EQ(kept.rows(), rows);
  EXPECT_FALSE(std::filesystem::exists(dir / "experiment_validation.csv"));
}

// An arm resting with the elbow inside the margin of its lower stop (0.60 rad; the limit is
// 0.586 rad and the experiment keeps 0.05 rad from it): identify refuses before anything moves,
// naming --hold-angle and the range; given a hold angle, each experiment first moves the elbow
// there through the fake DAQ and excites it about it.
TEST(IdentifyCli, AJointRestingInsideItsMarginIsRefusedUntilAHoldAngleMovesItOut) {
  const auto dir = tempDir("hold_angle");
  std::ifstream shipped(fullarm::arm::test::sourcePath("config/dts_master.yaml"));
  std::string arm_text((std::istreambuf_iterator<char>(shipped)), std::istreambuf_iterator<char>());
  const std::string elbow_default = "default_rad: 1.57";
  const std::size_t at = arm_text.find(elbow_default);
  ASSERT_NE(at, std::string::npos);
  ASSERT_EQ(arm_text.find(elbow_default, at + 1), std::string::npos);
  arm_text.replace(at, elbow_default.size(), "default_rad: 0.60");
  const std::string arm = (dir / "arm_elbow_at_rest.yaml").string();
  { std::ofstream(arm) << arm_text; }

  for (const char* io : {"sim", "fakedaq"}) {
    const Result refused =
        runFullarm(std::string("identify --quiet --io ") + io + " --joint EB --duration 1 --config " + arm + " --out " +
                   (dir / "refused").string());
    EXPECT_EQ(refused.exit_code, 2) << io << "\n" << refused.output;
    for (const char* named : {"--hold-angle", "R_EB starts at 0.6", "expected it inside 0.636132..2.158897 rad"}) {
      EXPECT_NE(refused.output.find(named), std::string::npos) << io << ": expected '" << named << "' in\n"
                                                               << refused.output;
    }
  }

  // With --io sim the simulated DTS starts at the hold angle: the hold law recovered from the
  // logs is about it (its first reading, within the potentiometer's noise and counts).
  const auto started = dir / "started";
  const Result sim = runFullarm("identify --quiet --io sim --joint EB --duration 1 --hold-angle 1.2 --config " + arm +
                                " --out " + started.string());
  ASSERT_TRUE(sim.exit_code == 0 || sim.exit_code == 1) << sim.output;
  for (const nlohmann::json& e : readSummary(started)["results"]["identify"]["experiments"]) {
    EXPECT_NEAR(e["hold_rad"].get<double>(), 1.2, 0.002) << e.dump();
  }

  const auto moved = dir / "moved";
  const Result r = runFullarm("identify --quiet --io fakedaq --joint EB --duration 1 --hold-angle 1.2 --config " + arm +
                              " --out " + moved.string());
  ASSERT_TRUE(r.exit_code == 0 || r.exit_code == 1) << r.output;
  const nlohmann::json result = readSummary(moved)["results"]["identify"];
  for (const nlohmann::json& e : result["experiments"]) {
    EXPECT_TRUE(e["completed"].get<bool>()) << e.dump();
    // The hold law recovered from the log is the one about the hold angle.
    EXPECT_NEAR(e["hold_rad"].get<double>(), 1.2, 1e-6) << e.dump();
  }
  // The elbow moved 0.6 rad from its rest and was excited about the hold angle, below it by the
  // proportional hold's droop: the valve command that holds the gravity load against the leakage
  // (about 0.35 V) over the hold's 10 V/rad, 0.035 rad.
  for (const char* log : {"experiment_fit.csv", "experiment_validation.csv"}) {
    const id::SignalTable table = id::readSignalCsv(moved / log, id::kExperimentColumns);
    double mean = 0.0;
    for (double q : table.column("q_rad")) mean += q;
    mean /= static_cast<double>(table.rows());
    EXPECT_NEAR(mean, 1.2, 0.05) << log;
  }
}

TEST(IdentifyCli, BackEndOptionsOutOfPlaceExitTwoNamingTheOption) {
  const auto dir = tempDir("io_bad");
  const std::string file = (dir / "any.yaml").string();
  { std::ofstream(file) << "x: 1\n"; }
  const std::string log = (dir / "log.csv").string();
  { std::ofstream(log) << "time_s,excitation_v,command_v,q_rad,tau_measured_nm\n"; }
  const auto expectBad = [&](const std::string& args, const std::string& named) {
    const Result r = runFullarm("identify --quiet --duration 1 --out " + dir.string() + " " + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_NE(r.output.find(named), std::string::npos) << args << ": expected '" << named << "' in\n" << r.output;
  };
  expectBad("--io sim --daq-config " + file, "--daq-config");
  expectBad("--io sim --hil-config " + file, "--hil-config");
  expectBad("--io comedi --seed 3", "--seed");
  expectBad("--io udp", "--io");
  expectBad("--io sim --lcm-url udpm://239.255.76.98:7698?ttl=0", "--lcm-url");
  expectBad("--io lcm --seed 3", "--seed");
  expectBad("--io lcm --daq-config " + file, "--daq-config");
  expectBad("--log " + log + " " + log + " --lcm-url udpm://239.255.76.98:7698?ttl=0", "--lcm-url");
  expectBad("--log " + log + " " + log + " --daq-config " + file, "--daq-config");
  expectBad("--log " + log + " " + log + " --seed 2", "--seed");
  expectBad("--log " + log + " " + log + " --hold-angle 1.2", "--hold-angle");
  // The move to a hold angle on the real arm needs the workspace confirmed; the confirmation is
  // refused where nothing real moves. With it, the command goes on to open the board.
  expectBad("--io comedi --hold-angle 1.2", "--confirm-arm-motion: is required with --hold-angle");
  expectBad("--io comedi --confirm-arm-motion", "--confirm-arm-motion");
  expectBad("--io sim --hold-angle 1.2 --confirm-arm-motion", "--confirm-arm-motion");
  expectBad("--io fakedaq --hold-angle 1.2 --confirm-arm-motion", "--confirm-arm-motion");
  expectBad("--log " + log + " " + log + " --confirm-arm-motion", "--confirm-arm-motion");
  expectBad("--io comedi --hold-angle 1.2 --confirm-arm-motion", "/dev/comedi0");
  // No board on this machine: the error names the device file of the channel map.
  expectBad("--io comedi", "/dev/comedi0");
  // A channel map that wires the elbow's chamber pressures, on the shipped plant, which has no
  // transducers: the map's file and key.
  std::ifstream shipped(fullarm::arm::test::sourcePath("config/dts_daq.yaml"));
  std::string map_text((std::istreambuf_iterator<char>(shipped)), std::istreambuf_iterator<char>());
  const std::string elbow_valve = "valve: {channel: 3, calibration: {type: linear, scale: 1.0, offset: 0.0}}";
  const std::size_t at = map_text.find(elbow_valve);
  ASSERT_NE(at, std::string::npos);
  map_text.insert(at + elbow_valve.size(),
                  "\n    pressure_a: {channel: 7, calibration: {type: linear, scale: 2.5e6, offset: 0.0}}"
                  "\n    pressure_b: {channel: 15, calibration: {type: linear, scale: 2.5e6, offset: 0.0}}");
  const std::string map = (dir / "pressure_map.yaml").string();
  { std::ofstream(map) << map_text; }
  expectBad("--io fakedaq --joint EB --daq-config " + map, "pressure_map.yaml");
  expectBad("--io fakedaq --joint EB --daq-config " + map, "joints[3].pressure_a");
}

}  // namespace
