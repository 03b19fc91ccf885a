// The DTS reference's identified gravity on our kinematics against the torques SL's generated
// code gives at the published static postures, and the consistent set fitted to it.

#include "fullarm/identification/reference_gravity.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include <filesystem>
#include <fstream>
#include <sstream>
#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/identification/gravity_yaml.hpp"

namespace fullarm::identification {
namespace {

TEST(ReferenceGravityTest, ReferenceSetReproducesThePublishedStaticTorques) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const arm::ArmModel reference = withReferenceGravity(model);
  arm::ArmData data(reference);
  for (const auto& hold : publishedGravity()) {
    Eigen::VectorXd q = model.defaultPosture();
    for (int k = 0; k < 7; ++k) q[k] = hold.q_rad[static_cast<std::size_t>(k)];
    arm::computeGravityTorques(reference, data, q);
    for (int k = 0; k < 7; ++k) {
      // Six printed decimals on the inputs and the outputs (as the inverse-dynamics oracle).
      EXPECT_NEAR(data.tau_gravity[k], hold.tau_nm[static_cast<std::size_t>(k)], 2e-6) << "joint " << k;
    }
  }
}

TEST(ReferenceGravityTest, ConsistentFitMatchesTheReferenceBetterThanTheDefault) {
  const arm::ArmModel& model = arm::test::defaultModel();
  ReferenceFitOptions options;
  options.train_postures = 120;
  options.heldout_postures = 60;
  const ReferenceGravityFit result = fitToReferenceGravity(model, options);
  EXPECT_TRUE(result.fit.positive_masses);
  EXPECT_TRUE(result.fit.centres_inside);
  for (int k = 0; k < 7; ++k) {
    std::printf(
        "%-6s held-out RMS: fitted %.2e, default %.4f N m; gain fitted %.4f default %.3f; published max %.2e N m\n",
        result.joints[static_cast<std::size_t>(k)].c_str(), result.fitted_vs_reference.heldout_rms_nm[k],
        result.nominal_vs_reference.heldout_rms_nm[k], result.fitted_vs_reference.gain[k],
        result.nominal_vs_reference.gain[k], result.fitted_vs_reference.published_max_nm[k]);
  }
  for (std::size_t i = 0; i < model.joints.size(); ++i) {
    const auto& in = result.fitted.joints[i].inertial;
    std::printf("%-6s m %.4f kg (default %.3f) c (%.4f, %.4f, %.4f) m\n", model.joints[i].name.c_str(), in.mass_kg,
                model.joints[i].inertial.mass_kg, in.com_m.x(), in.com_m.y(), in.com_m.z());
  }
  // The default is 25-30 % stronger than the reference on the shoulder and elbow (docs/arm-model.md).
  EXPECT_GT(result.nominal_vs_reference.gain[1], 1.2);
  EXPECT_GT(result.nominal_vs_reference.gain[3], 1.2);
  EXPECT_LT(result.fitted_vs_reference.heldout_rms_nm.norm(), 0.5 * result.nominal_vs_reference.heldout_rms_nm.norm());
  EXPECT_LT(result.fitted_vs_reference.heldout_rms_nm.maxCoeff(), 1e-5);  // the reference's six printed decimals
  EXPECT_LT(result.fitted_vs_reference.published_max_nm.maxCoeff(), 1e-5);
}

TEST(ReferenceGravityTest, RefittingFromTheFittedSetOnItsBoundsReturnsTheSameGravity) {
  // The fitted set has active bounds (centres of mass on their capsules, masses at the minimum):
  // as a nominal it lies on the boundary, and the fit still starts strictly inside.
  ReferenceFitOptions options;
  options.train_postures = 60;
  options.heldout_postures = 20;
  const ReferenceGravityFit first = fitToReferenceGravity(arm::test::defaultModel(), options);
  const ReferenceGravityFit again = fitToReferenceGravity(first.fitted, options);
  EXPECT_TRUE(again.fit.centres_inside);
  // The published torques have six decimals: the fit reproduces them to that precision.
  EXPECT_LT(again.fitted_vs_reference.heldout_rms_nm.maxCoeff(), 1e-5);
  EXPECT_LT(again.fitted_vs_reference.published_max_nm.maxCoeff(), 1e-5);
}

TEST(ReferenceGravityTest, FittedSetWrittenAsArmYamlReadsBackToTheSameGravity) {
  const std::string path = arm::test::sourcePath("config/dts_master.yaml");
  std::ifstream in(path);
  std::ostringstream text;
  text << in.rdbuf();
  const arm::ArmModel source = arm::parseArmModel(text.str(), path);
  ReferenceFitOptions options;
  options.train_postures = 60;
  options.heldout_postures = 10;
  const ReferenceGravityFit result = fitToReferenceGravity(source, options);
  const std::string yaml = armYamlWithGravity(text.str(), path, source, result.fitted, "fitted");
  const arm::ArmModel read = arm::parseArmModel(yaml, path);
  ASSERT_EQ(read.joints.size(), source.joints.size());
  for (std::size_t i = 0; i < read.joints.size(); ++i) {
    const auto& got = read.joints[i].inertial;
    const auto& want = result.fitted.joints[i].inertial;
    EXPECT_NEAR(got.mass_kg, want.mass_kg, 1e-9 * (1.0 + want.mass_kg)) << read.joints[i].name;
    EXPECT_LT((got.com_m - want.com_m).norm(), 1e-9) << read.joints[i].name;
    // Inertia: the source's scaled by the mass ratio.
    const double ratio =
        source.joints[i].inertial.mass_kg > 0.0 ? want.mass_kg / source.joints[i].inertial.mass_kg : 1.0;
    EXPECT_LT((got.inertia_com_kgm2 - ratio * source.joints[i].inertial.inertia_com_kgm2).norm(),
              1e-9 * (1.0 + got.inertia_com_kgm2.norm()))
        << read.joints[i].name;
    EXPECT_EQ(read.joints[i].dh.has_value(), source.joints[i].dh.has_value());
    if (read.joints[i].dh && source.joints[i].dh) {
      EXPECT_EQ(read.joints[i].dh->d_m, source.joints[i].dh->d_m);
    }
  }
  arm::ArmData a(read);
  arm::ArmData b(result.fitted);
  for (const auto& hold : publishedGravity()) {
    Eigen::VectorXd q = source.defaultPosture();
    for (int k = 0; k < 7; ++k) q[k] = hold.q_rad[static_cast<std::size_t>(k)];
    arm::computeGravityTorques(read, a, q);
    arm::computeGravityTorques(result.fitted, b, q);
    EXPECT_LT((a.tau_gravity - b.tau_gravity).cwiseAbs().maxCoeff(), 1e-7);
  }
  // The header names the source by its file name and the note; the source's own text follows.
  const std::string name = std::filesystem::path(path).filename().string();
  EXPECT_EQ(yaml.rfind("# The arm file " + name + " with the gravity set of the links marked\n# \"fitted\"", 0), 0u)
      << yaml.substr(0, 300);
  EXPECT_NE(yaml.find("#\n" + text.str().substr(0, 40)), std::string::npos);
  // Written again from a written file, the earlier header gives way: one header, the new note.
  const std::string again = armYamlWithGravity(yaml, "out/arm.yaml", read, source, "refitted");
  // The inertia comments are not prefixed twice either.
  EXPECT_EQ(again.find("scaled to the fitted mass from: scaled to the fitted mass from:"), std::string::npos);
  EXPECT_EQ(again.rfind("# The arm file arm.yaml with the gravity set of the links marked\n# \"refitted\"", 0), 0u)
      << again.substr(0, 300);
  EXPECT_EQ(again.find("\"fitted\""), std::string::npos);
  EXPECT_NE(again.find("#\n" + text.str().substr(0, 40)), std::string::npos);
}

}  // namespace
}  // namespace fullarm::identification
