// The loop closes: on a simulated elbow whose valve flow gain is four times and whose chambers'
// dead volumes are 0.7 times the shipped plant's, the shipped gains fail `validate`; `identify`
// on that plant (started from the shipped plant's groups) writes a plant file whose groups lie
// within 10 % of the perturbed plant's own (greyModelFromJoint), and `tune` on that file gives
// gains that pass `validate` on the perturbed plant. Only the elbow is tuned (the tuner's
// per-joint path, --joints EB): the whole arm's tune takes minutes and the other joints are
// unchanged. Friction is left out of the 10 % check: on the simulated plant it is not recovered
// (docs/identification.md).

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "cli_runner.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/identification/identified_model.hpp"
#include "fullarm/identification/joint_groups.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace {

using fullarm::test::runFullarm;
namespace id = fullarm::identification;
namespace plant = fullarm::plant;
namespace arm = fullarm::arm;

constexpr double kFlowFactor = 4.0;
constexpr double kDeadVolumeFactor = 0.7;

nlohmann::json readSummary(const std::filesystem::path& dir) {
  std::ifstream in(dir / "summary.json");
  return nlohmann::json::parse(in);
}

void writeText(const std::filesystem::path& file, const std::string& text) {
  std::ofstream out(file);
  out << text;
}

TEST(IdentifyTuneLoop, IdentifiedPlantGivesGainsThatPassWhereTheShippedOnesFail) {
  const auto dir = fullarm::test::cliTempDir("fullarm_identify_tune_loop_test", "loop");
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  const plant::PlantConfig shipped = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  const int eb = plant::findPlantJoint(shipped, "EB");
  const int model_eb = model.jointIndex("R_EB");

  // The perturbed plant (the truth).
  plant::PlantConfig truth = shipped;
  plant::JointParams& j = truth.joints[static_cast<std::size_t>(eb)];
  j.valve.rated_flow_m3ps *= kFlowFactor;
  j.chambers.dead_volume_a_m3 *= kDeadVolumeFactor;
  j.chambers.dead_volume_b_m3 *= kDeadVolumeFactor;
  const auto truth_file = dir / "perturbed_plant.yaml";
  writeText(truth_file, plant::formatPlantConfigYaml(truth, model));

  // The fit starts from the shipped plant's groups at the default posture.
  const Eigen::VectorXd q0 = model.defaultPosture();
  arm::ArmData data(model);
  arm::computeMassMatrix(model, data, q0);
  arm::computeGravityTorques(model, data, q0);
  id::IdentifiedModel start;
  start.joint = "R_EB";
  start.model = id::greyModelFromJoint(shipped.joints[static_cast<std::size_t>(eb)], q0[model_eb],
                                       data.mass_matrix(model_eb, model_eb), data.tau_gravity[model_eb], 1);
  const auto start_file = dir / "start.yaml";
  writeText(start_file, id::formatIdentifiedModelYaml(start));

  // 1. The shipped gains fail on the perturbed plant.
  const auto shipped_val = dir / "validate_shipped";
  const auto r1 = runFullarm("validate --quiet --joints EB --samples 20 --plant " + truth_file.string() + " --out " +
                             shipped_val.string());
  ASSERT_EQ(r1.exit_code, 1) << r1.output;
  EXPECT_FALSE(readSummary(shipped_val)["results"]["validate"]["pass"].get<bool>());

  // 2. Identify on it (excitation scaled down with the faster valve, so the load cell stays in range).
  const auto identified_dir = dir / "identify";
  const auto r2 = runFullarm("identify --quiet --joint EB --duration 4 --amplitude 0.1 --plant " + truth_file.string() +
                             " --start " + start_file.string() + " --out " + identified_dir.string());
  ASSERT_TRUE(r2.exit_code == 0 || r2.exit_code == 1) << r2.output;
  const auto plant_file = identified_dir / "identified_plant.yaml";
  ASSERT_TRUE(std::filesystem::exists(plant_file)) << r2.output;
  const nlohmann::json result = readSummary(identified_dir)["results"]["identify"];
  const double q_hold = result["experiments"][0]["hold_rad"].get<double>();
  Eigen::VectorXd q = q0;
  q[model_eb] = q_hold;
  arm::computeMassMatrix(model, data, q);
  const double link_inertia = data.mass_matrix(model_eb, model_eb);
  const id::GreyModel want = id::greyModelFromJoint(j, q_hold, link_inertia, 0.0, 1);
  const plant::PlantConfig identified = plant::loadPlantConfig(plant_file, model);
  const id::GreyModel got =
      id::greyModelFromJoint(identified.joints[static_cast<std::size_t>(eb)], q_hold, link_inertia, 0.0, 1);
  for (const int i : {id::kFlowGain, id::kStiffness, id::kLeakage, id::kInertia}) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_NEAR(got.value[k], want.value[k], 0.1 * want.value[k]) << id::greyParamName(i);
    // The identified values themselves, as the summary reports them.
    EXPECT_NEAR(result["parameters"][id::greyParamName(i)]["value"].get<double>(), want.value[k], 0.1 * want.value[k])
        << id::greyParamName(i);
  }

  // 3. Tune the elbow on the identified plant; the gains pass on the perturbed plant.
  const auto tuned = dir / "tune";
  const auto r3 = runFullarm("tune --quiet --joints EB --plant " + plant_file.string() + " --out " + tuned.string());
  ASSERT_EQ(r3.exit_code, 0) << r3.output;
  const auto tuned_val = dir / "validate_tuned";
  const auto r4 = runFullarm("validate --quiet --joints EB --samples 20 --plant " + truth_file.string() + " --gains " +
                             (tuned / "gains.yaml").string() + " --out " + tuned_val.string());
  EXPECT_EQ(r4.exit_code, 0) << r4.output;
  EXPECT_TRUE(readSummary(tuned_val)["results"]["validate"]["pass"].get<bool>());
}

}  // namespace
