// Loading config/dts_master.yaml, and one test per kind of bad input: each error must name the
// file, the key path and what was expected.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/core/config_error.hpp"
#include "scratch_dir.hpp"

namespace fullarm::arm {
namespace {

std::string defaultText() {
  std::ifstream in(test::sourcePath("config/dts_master.yaml"));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// Default YAML with the first occurrence of `from` replaced by `to` (the test fails if absent).
std::string edited(const std::string& from, const std::string& to) {
  std::string text = defaultText();
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "fixture text not found: " << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::filesystem::path writeTemp(const std::string& name, const std::string& text) {
  static const std::filesystem::path dir = fullarm::test::scratchDir("fullarm_model_loading_test");
  const std::filesystem::path file = dir / name;
  std::ofstream(file) << text;
  return file;
}

// Loads `text` from a file and returns the core::ConfigError; fails the test if loading succeeds.
core::ConfigError loadError(const std::string& name, const std::string& text) {
  const std::filesystem::path file = writeTemp(name, text);
  try {
    (void)loadArmModel(file);
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    return e;
  }
  ADD_FAILURE() << "loading " << name << " succeeded";
  return core::ConfigError(file, "", "no error");
}

TEST(ModelLoading, DefaultModelLoadsWithPublishedFigures) {
  const ArmModel& model = test::defaultModel();
  EXPECT_EQ(model.name, "sarcos_dts_master");
  ASSERT_EQ(model.numJoints(), 10);
  EXPECT_EQ(model.numArmJoints(), 7);
  const char* names[] = {"R_SFE", "R_SAA", "R_HR", "R_EB", "R_WR", "R_WFE", "R_WAA", "R_TL", "R_TV", "R_FAA"};
  for (int i = 0; i < 10; ++i) EXPECT_EQ(model.joints[static_cast<std::size_t>(i)].name, names[i]);
  // Reference section 3: R_EB range and default posture.
  EXPECT_DOUBLE_EQ(model.joints[3].limits.min_rad, 0.586132);
  EXPECT_DOUBLE_EQ(model.joints[3].limits.max_rad, 2.208897);
  EXPECT_DOUBLE_EQ(model.defaultPosture()[1], -0.30);
  EXPECT_DOUBLE_EQ(model.defaultPosture()[3], 1.57);
  EXPECT_EQ(model.joints[2].actuator.type, ActuatorGeometry::Type::kRotary);
  EXPECT_EQ(model.joints[0].actuator.type, ActuatorGeometry::Type::kLinear);
  EXPECT_NEAR(model.totalMass(), 2.0 + 2.0 + 6.8 + 1.0 + 3.36 + 1.34 + 0.90 + 0.05 + 0.05, 1e-12);
  EXPECT_EQ(model.joints[static_cast<std::size_t>(model.upper_arm_joint)].name, "R_HR");
  EXPECT_EQ(model.joints[static_cast<std::size_t>(model.forearm_joint)].name, "R_WR");
}

TEST(ModelLoading, ParseFromTextEqualsLoadFromFile) {
  const ArmModel parsed = parseArmModel(defaultText(), test::sourcePath("config/dts_master.yaml"));
  const ArmModel& loaded = test::defaultModel();
  ASSERT_EQ(parsed.numJoints(), loaded.numJoints());
  for (std::size_t i = 0; i < parsed.joints.size(); ++i) {
    EXPECT_TRUE(parsed.joints[i].X_PL0.isApprox(loaded.joints[i].X_PL0));
  }
}

TEST(ModelLoading, MissingKeyIsNamed) {
  const core::ConfigError e = loadError("missing.yaml", edited("    default_rad: -0.30\n", ""));
  EXPECT_EQ(e.keyPath(), "joints[1].default_rad");
  EXPECT_NE(e.message().find("missing required key 'default_rad'"), std::string::npos) << e.what();
  EXPECT_GT(e.line(), 0);
}

TEST(ModelLoading, WrongTypeIsNamed) {
  const core::ConfigError e = loadError("wrong_type.yaml", edited("mass_kg: 6.8", "mass_kg: heavy"));
  EXPECT_EQ(e.keyPath(), "joints[2].link.mass_kg");
  EXPECT_NE(e.message().find("expected a finite number (kg), got 'heavy'"), std::string::npos) << e.what();
}

TEST(ModelLoading, WrongContainerTypeIsNamed) {
  const core::ConfigError e = loadError("wrong_list.yaml", edited("com_m: [0.0, 0.0, -0.188]", "com_m: 0.188"));
  EXPECT_EQ(e.keyPath(), "joints[2].link.com_m");
  EXPECT_NE(e.message().find("expected a list of 3 finite numbers"), std::string::npos) << e.what();
}

TEST(ModelLoading, NegativeMassIsRejected) {
  const core::ConfigError e = loadError("negative_mass.yaml", edited("mass_kg: 3.36", "mass_kg: -3.36"));
  EXPECT_EQ(e.keyPath(), "joints[4].link.mass_kg");
  EXPECT_NE(e.message().find("expected a mass >= 0 kg"), std::string::npos) << e.what();
  EXPECT_GT(e.line(), 0);
}

TEST(ModelLoading, NonPositiveDefiniteInertiaIsRejected) {
  const core::ConfigError e = loadError(
      "not_pd.yaml", edited("{xx: 0.050926, yy: 0.050926, zz: 0.0085,", "{xx: 0.050926, yy: 0.050926, zz: -0.0085,"));
  EXPECT_EQ(e.keyPath(), "joints[2].link.inertia_kgm2");
  EXPECT_NE(e.message().find("positive definite"), std::string::npos) << e.what();
}

// Positive definite, but one principal moment exceeds the sum of the other two: no rigid body.
TEST(ModelLoading, TriangleInequalityViolationIsRejected) {
  const core::ConfigError e =
      loadError("triangle.yaml", edited("{xx: 0.022999, yy: 0.022999, zz: 0.002688, xy: 0.0, xz: 0.0, yz: 0.0}",
                                        "{xx: 0.001, yy: 0.001, zz: 0.003, xy: 0.0, xz: 0.0, yz: 0.0}"));
  EXPECT_EQ(e.keyPath(), "joints[4].link.inertia_kgm2");
  EXPECT_NE(e.message().find("triangle inequality"), std::string::npos) << e.what();
}

// The identified R_WR inertia of the SL set (reference section 4.4) is positive definite but
// no rigid body has it: the loader must say so.
TEST(ModelLoading, IdentifiedSlInertiaIsRejected) {
  const core::ConfigError e =
      loadError("sl_inertia.yaml",
                edited("{xx: 0.022999, yy: 0.022999, zz: 0.002688, xy: 0.0, xz: 0.0, yz: 0.0}",
                       "{xx: 0.023417, yy: 0.000012, zz: 0.003393, xy: -0.000240, xz: 0.008912, yz: -0.000088}"));
  EXPECT_EQ(e.keyPath(), "joints[4].link.inertia_kgm2");
  EXPECT_TRUE(e.message().find("triangle inequality") != std::string::npos ||
              e.message().find("positive definite") != std::string::npos)
      << e.what();
}

TEST(ModelLoading, ReversedLimitsAreRejected) {
  const core::ConfigError e = loadError(
      "reversed.yaml", edited("{min_rad: 0.586132, max_rad: 2.208897,", "{min_rad: 2.208897, max_rad: 0.586132,"));
  EXPECT_EQ(e.keyPath(), "joints[3].limits");
  EXPECT_NE(e.message().find("expected min_rad < max_rad"), std::string::npos) << e.what();
}

TEST(ModelLoading, UnknownKeyIsRejected) {
  const core::ConfigError e =
      loadError("unknown.yaml", edited("    default_rad: 1.57\n", "    default_rad: 1.57\n    dampng: 3\n"));
  EXPECT_EQ(e.keyPath(), "joints[3].dampng");
  EXPECT_NE(e.message().find("unknown key"), std::string::npos) << e.what();
}

TEST(ModelLoading, UnknownTopLevelKeyIsRejected) {
  const core::ConfigError e = loadError("unknown_top.yaml", defaultText() + "\nextra_setting: 1\n");
  EXPECT_EQ(e.keyPath(), "extra_setting");
}

TEST(ModelLoading, DuplicateKeyIsRejected) {
  const core::ConfigError e = loadError(
      "duplicate_key.yaml", edited("    default_rad: 1.57\n", "    default_rad: 1.57\n    default_rad: 2.0\n"));
  EXPECT_EQ(e.keyPath(), "joints[3].default_rad");
  EXPECT_NE(e.message().find("duplicate key"), std::string::npos) << e.what();
  EXPECT_GT(e.line(), 0);
}

TEST(ModelLoading, ArmJointWithoutDhIsRejected) {
  ArmModel model = test::defaultModel();
  model.joints[2].dh.reset();
  EXPECT_THROW(validateArmModel(model), core::ConfigError);
  model = test::defaultModel();
  model.joints[2].X_PL0.translation().z() += 0.01;  // no longer the DH transform
  try {
    validateArmModel(model);
    FAIL() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_EQ(e.keyPath(), "joints[2].dh");
  }
}

TEST(ModelLoading, YamlSyntaxErrorHasALine) {
  const core::ConfigError e = loadError("syntax.yaml", edited("name: sarcos_dts_master", "name: [unclosed"));
  EXPECT_NE(e.message().find("YAML syntax error"), std::string::npos) << e.what();
  EXPECT_GT(e.line(), 0);
}

TEST(ModelLoading, MissingFileIsNamed) {
  try {
    (void)loadArmModel("/nonexistent/arm.yaml");
    FAIL() << "no error";
  } catch (const core::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/arm.yaml"), std::string::npos);
    EXPECT_NE(e.message().find("cannot open"), std::string::npos);
  }
}

TEST(ModelLoading, DefaultOutsideLimitsIsRejected) {
  const core::ConfigError e = loadError("default.yaml", edited("default_rad: 1.57", "default_rad: 3.0"));
  EXPECT_EQ(e.keyPath(), "joints[3].default_rad");
}

TEST(ModelLoading, DuplicateJointNameIsRejected) {
  const core::ConfigError e = loadError("duplicate.yaml", edited("- name: R_SAA ", "- name: R_SFE "));
  EXPECT_EQ(e.keyPath(), "joints[1].name");
}

TEST(ModelLoading, ImpossibleCylinderIsRejected) {
  const core::ConfigError e = loadError("cylinder.yaml", edited("moment_arm_m: 0.03175, mount_distance_m: 0.1397",
                                                                "moment_arm_m: 0.2, mount_distance_m: 0.1397"));
  EXPECT_EQ(e.keyPath(), "joints[3].actuator");
}

TEST(ModelLoading, RangeBeyondThePotentiometerIsRejected) {
  const core::ConfigError e = loadError("pot.yaml", edited("max_rad: 1.370363", "max_rad: 1.6"));
  EXPECT_EQ(e.keyPath(), "joints[0].limits");
  EXPECT_NE(e.message().find("potentiometer"), std::string::npos) << e.what();
}

TEST(ModelLoading, UnknownParentIsRejected) {
  const core::ConfigError e = loadError("parent.yaml", edited("parent: R_TL", "parent: R_NOPE"));
  EXPECT_EQ(e.keyPath(), "hand_joints[1].parent");
}

TEST(ModelLoading, MissingMeshFileIsRejected) {
  const core::ConfigError e =
      loadError("mesh.yaml",
                edited("geometry: {type: capsule, radius_m: 0.04, from_m: [0.0, 0.0, -0.2781], to_m: [0.0, 0.0, 0.0]}",
                       "geometry: {type: mesh, file: no_such_mesh.stl, scale: 1.0, pose: {translation_m: [0, 0, 0], "
                       "rpy_deg: [0, 0, 0]}}"));
  EXPECT_EQ(e.keyPath(), "joints[4].link.geometry.file");
  EXPECT_NE(e.message().find("no_such_mesh.stl"), std::string::npos);
}

// Fuzz-style: random byte edits of the default file must either load or raise core::ConfigError with
// a non-empty message; never crash, never another exception type.
TEST(ModelLoading, RandomCorruptionsGiveConfigErrorsOnly) {
  const std::string base = defaultText();
  std::mt19937 rng(99);
  const std::string alphabet = "-:[]{},#.0123456789eE abcxyz\n\t'\"";
  std::uniform_int_distribution<std::size_t> pos(0, base.size() - 1);
  std::uniform_int_distribution<std::size_t> chr(0, alphabet.size() - 1);
  std::uniform_int_distribution<int> edits(1, 6);
  int rejected = 0;
  constexpr int kCases = 400;
  for (int trial = 0; trial < kCases; ++trial) {
    std::string text = base;
    const int n = edits(rng);
    for (int k = 0; k < n; ++k) {
      const std::size_t at = pos(rng) % text.size();
      switch (rng() % 3) {
        case 0:
          text[at] = alphabet[chr(rng)];
          break;
        case 1:
          text.erase(at, 1 + rng() % 8);
          break;
        default:
          text.insert(at, 1, alphabet[chr(rng)]);
          break;
      }
    }
    try {
      (void)parseArmModel(text, "fuzz.yaml");
    } catch (const core::ConfigError& e) {
      ++rejected;
      EXPECT_FALSE(e.message().empty());
      EXPECT_NE(std::string(e.what()).find("fuzz.yaml"), std::string::npos);
    }
  }
  // Most random edits break something; the test would be vacuous if none did.
  EXPECT_GT(rejected, kCases / 4);
}

}  // namespace
}  // namespace fullarm::arm
