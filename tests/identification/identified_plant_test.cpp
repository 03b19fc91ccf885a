// A plant joint carrying identified groups: written as plant YAML and read back, its own groups
// (greyModelFromJoint, tested against Merritt's formulas in joint_groups_test) are the identified
// ones, everything else is the starting plant's, and groups no plant parameter can carry are
// refused with the group named.

#include "fullarm/identification/identified_plant.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/identification/joint_groups.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::identification {
namespace {

constexpr double kQ = 1.2;
constexpr double kLinkInertia = 0.2;

struct Fixture {
  arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  plant::PlantConfig plant = plant::loadPlantConfig(plant::defaultPlantConfigPath(), model);
  int eb = plant::findPlantJoint(plant, "EB");
  const plant::JointParams& start() const { return plant.joints[static_cast<std::size_t>(eb)]; }
};

GreyModel perturbedGroups(const plant::JointParams& start) {
  GreyModel g = greyModelFromJoint(start, kQ, kLinkInertia, 3.0, 1);
  g.value[kFlowGain] *= 1.3;
  g.value[kStiffness] *= 0.7;
  g.value[kLeakage] *= 2.0;
  g.value[kInertia] += 0.05;
  g.value[kViscous] = 0.3;
  g.value[kCoulomb] = 0.7;
  g.value[kStribeck] = 0.2;
  return g;
}

std::string refusal(const plant::JointParams& start, const GreyModel& g, double link_inertia = kLinkInertia) {
  try {
    static_cast<void>(plantJointWithGroups(start, g, kQ, link_inertia));
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "(accepted)";
}

TEST(IdentifiedPlantTest, WrittenPlantReadsBackWithTheIdentifiedGroups) {
  Fixture f;
  const GreyModel groups = perturbedGroups(f.start());
  plant::PlantConfig identified = f.plant;
  const IdentifiedPlantJoint carried = plantJointWithGroups(f.start(), groups, kQ, kLinkInertia);
  EXPECT_TRUE(carried.notes.empty());
  identified.joints[static_cast<std::size_t>(f.eb)] = carried.joint;
  const std::string yaml = plant::formatPlantConfigYaml(identified, f.model, {"identified"});
  const plant::PlantConfig back = plant::parsePlantConfig(yaml, "identified_plant.yaml", f.model);
  const plant::JointParams& j = back.joints[static_cast<std::size_t>(f.eb)];
  const GreyModel own = greyModelFromJoint(j, kQ, kLinkInertia, 3.0, 1);
  for (const int i : {kFlowGain, kStiffness, kLeakage, kInertia, kViscous, kCoulomb, kStribeck}) {
    const double want = groups.value[static_cast<std::size_t>(i)];
    EXPECT_NEAR(own.value[static_cast<std::size_t>(i)], want, 1e-9 * std::abs(want)) << greyParamName(i);
  }
  // The fixed structure is unchanged, so is everything the mapping does not designate.
  EXPECT_DOUBLE_EQ(own.stall_torque_nm, groups.stall_torque_nm);
  EXPECT_DOUBLE_EQ(own.underlap_v, groups.underlap_v);
  EXPECT_DOUBLE_EQ(own.edge_rounding_v, groups.edge_rounding_v);
  EXPECT_DOUBLE_EQ(j.valve.amplifier_gain_per_v, f.start().valve.amplifier_gain_per_v);
  EXPECT_DOUBLE_EQ(j.actuator.piston_area_a_m2, f.start().actuator.piston_area_a_m2);
  EXPECT_DOUBLE_EQ(j.fluid.oil_bulk_modulus_pa, f.start().fluid.oil_bulk_modulus_pa);
  EXPECT_DOUBLE_EQ(j.chambers.dead_volume_a_m3 / j.chambers.dead_volume_b_m3,
                   f.start().chambers.dead_volume_a_m3 / f.start().chambers.dead_volume_b_m3);
  EXPECT_DOUBLE_EQ(j.sensor_noise.torque_bias_nm, f.start().sensor_noise.torque_bias_nm);
  // The other joints come back as they were.
  for (std::size_t k = 0; k < back.joints.size(); ++k) {
    if (static_cast<int>(k) == f.eb) continue;
    EXPECT_DOUBLE_EQ(back.joints[k].valve.rated_flow_m3ps, f.plant.joints[k].valve.rated_flow_m3ps);
    EXPECT_DOUBLE_EQ(back.joints[k].chambers.dead_volume_a_m3, f.plant.joints[k].chambers.dead_volume_a_m3);
    EXPECT_DOUBLE_EQ(back.joints[k].friction.coulomb_nm, f.plant.joints[k].friction.coulomb_nm);
  }
}

TEST(IdentifiedPlantTest, TheStartsOwnGroupsGiveTheStartBack) {
  Fixture f;
  const GreyModel own = greyModelFromJoint(f.start(), kQ, kLinkInertia, 0.0, 1);
  const plant::JointParams j = plantJointWithGroups(f.start(), own, kQ, kLinkInertia).joint;
  EXPECT_NEAR(j.valve.rated_flow_m3ps, f.start().valve.rated_flow_m3ps, 1e-12 * f.start().valve.rated_flow_m3ps);
  EXPECT_NEAR(j.chambers.dead_volume_a_m3, f.start().chambers.dead_volume_a_m3,
              1e-9 * f.start().chambers.dead_volume_a_m3);
  EXPECT_NEAR(j.chambers.internal_leakage_m3ps_per_pa, f.start().chambers.internal_leakage_m3ps_per_pa,
              1e-12 * f.start().chambers.internal_leakage_m3ps_per_pa);
  EXPECT_NEAR(j.actuator.inertia_kgm2, f.start().actuator.inertia_kgm2, 1e-12);
  EXPECT_DOUBLE_EQ(j.friction.static_nm, f.start().friction.static_nm);
}

// An inertia just below the link's (within the tolerance) leaves the actuator without inertia and
// says so; the plant's inertia group is then the link's.
TEST(IdentifiedPlantTest, AnInertiaJustBelowTheLinksIsCarriedAsTheLinksWithANote) {
  Fixture f;
  GreyModel g = perturbedGroups(f.start());
  g.value[kInertia] = (1.0 - 0.5 * kInertiaBelowLinkTolerance) * kLinkInertia;
  const IdentifiedPlantJoint carried = plantJointWithGroups(f.start(), g, kQ, kLinkInertia);
  EXPECT_EQ(carried.joint.actuator.inertia_kgm2, 0.0);
  ASSERT_EQ(carried.notes.size(), 1u);
  EXPECT_NE(carried.notes[0].find("5 % below the link's own 0.2 kg m^2"), std::string::npos) << carried.notes[0];
  EXPECT_DOUBLE_EQ(greyModelFromJoint(carried.joint, kQ, kLinkInertia, 0.0, 1).value[kInertia], kLinkInertia);
  g.value[kInertia] = (1.0 - 2.0 * kInertiaBelowLinkTolerance) * kLinkInertia;
  EXPECT_NE(refusal(f.start(), g).find("by more than 10 %"), std::string::npos) << refusal(f.start(), g);
}

TEST(IdentifiedPlantTest, GroupsNoPlantParameterCanCarryAreRefused) {
  Fixture f;
  const GreyModel good = perturbedGroups(f.start());

  GreyModel light = good;
  light.value[kInertia] = 0.5 * kLinkInertia;
  EXPECT_NE(refusal(f.start(), light).find("inertia_kgm2 is 0.1 kg m^2, below the link's own 0.2"), std::string::npos)
      << refusal(f.start(), light);

  GreyModel stiff = good;
  stiff.value[kStiffness] *= 1.0e4;
  EXPECT_NE(refusal(f.start(), stiff).find("hydraulic_stiffness_nm_per_rad"), std::string::npos)
      << refusal(f.start(), stiff);
  EXPECT_NE(refusal(f.start(), stiff).find("swept volume"), std::string::npos);

  GreyModel other_valve = good;
  other_valve.stall_torque_nm *= 1.5;
  EXPECT_NE(refusal(f.start(), other_valve).find("stall torque"), std::string::npos) << refusal(f.start(), other_valve);

  GreyModel other_spool = good;
  other_spool.spool_hz = 0.0;
  EXPECT_NE(refusal(f.start(), other_spool).find("spool natural frequency"), std::string::npos);

  GreyModel negative = good;
  negative.value[kLeakage] = -1e-3;
  EXPECT_NE(refusal(f.start(), negative).find("leakage_radps_per_nm is -0.001: expected >= 0"), std::string::npos)
      << refusal(f.start(), negative);

  GreyModel zero_gain = good;
  zero_gain.value[kFlowGain] = 0.0;
  EXPECT_NE(refusal(f.start(), zero_gain).find("flow_gain_radps_per_v is 0: expected > 0"), std::string::npos);
  EXPECT_NE(refusal(f.start(), zero_gain).find("R_EB"), std::string::npos);
}

}  // namespace
}  // namespace fullarm::identification
