// The uncertainty box: the sampler (inside its ranges, uniform by moments, a function of seed,
// joint and index only), the joint model of a variation (each parameter against its own scaling,
// computed here by hand) and the scenario of a variation (the same joint).

#include <gtest/gtest.h>

#include <cmath>

#include "design_fixture.hpp"
#include "fullarm/design/scenario_analysis.hpp"
#include "fullarm/design/uncertainty.hpp"

namespace fullarm::design {
namespace {

// Each drawn value lies in its range and the streams are uniform: sample means and variances
// match (a + b)/2 and (b - a)^2/12 within 5 standard errors; delays hit every integer equally.
TEST(Uncertainty, DrawsAreUniformInTheirRanges) {
  UncertaintyRanges r;
  r.bulk_modulus_scale = {0.5, 1.5};
  r.user_stiffness_nm_per_rad = {10.0, 70.0};
  r.delay_min_samples = 1;
  r.delay_max_samples = 3;
  const int n = 20000;
  double sum = 0.0, sum_sq = 0.0;
  int delays[4] = {0, 0, 0, 0};
  for (int i = 0; i < n; ++i) {
    const ModelVariation s = drawVariation(r, 42, 3, i);
    ASSERT_GE(s.bulk_modulus_scale, 0.5);
    ASSERT_LT(s.bulk_modulus_scale, 1.5);
    ASSERT_GE(s.user_stiffness_nm_per_rad, 10.0);
    ASSERT_LE(s.user_stiffness_nm_per_rad, 70.0);
    ASSERT_GE(s.delay_samples, 1);
    ASSERT_LE(s.delay_samples, 3);
    ++delays[s.delay_samples];
    sum += s.user_stiffness_nm_per_rad;
    sum_sq += s.user_stiffness_nm_per_rad * s.user_stiffness_nm_per_rad;
  }
  const double mean = sum / n;
  const double var = sum_sq / n - mean * mean;
  const double sigma = 60.0 / std::sqrt(12.0);
  EXPECT_NEAR(mean, 40.0, 5.0 * sigma / std::sqrt(n));
  EXPECT_NEAR(var, 3600.0 / 12.0, 5.0 * std::sqrt(0.8) * sigma * sigma / std::sqrt(n));  // var of s^2 for uniform
  for (int d = 1; d <= 3; ++d) EXPECT_NEAR(delays[d], n / 3.0, 5.0 * std::sqrt(n * (1.0 / 3) * (2.0 / 3))) << d;
}

TEST(Uncertainty, DrawsDependOnlyOnSeedJointAndIndex) {
  UncertaintyRanges r;
  const ModelVariation a = drawVariation(r, 7, 2, 11);
  // Draw others in between: no hidden state.
  for (int i = 0; i < 100; ++i) (void)drawVariation(r, 7, 5, i);
  const ModelVariation b = drawVariation(r, 7, 2, 11);
  EXPECT_EQ(a.bulk_modulus_scale, b.bulk_modulus_scale);
  EXPECT_EQ(a.user_damping_nms_per_rad, b.user_damping_nms_per_rad);
  EXPECT_EQ(a.delay_samples, b.delay_samples);
  EXPECT_NE(drawVariation(r, 7, 2, 12).bulk_modulus_scale, a.bulk_modulus_scale);
  EXPECT_NE(drawVariation(r, 8, 2, 11).bulk_modulus_scale, a.bulk_modulus_scale);
  EXPECT_NE(drawVariation(r, 7, 3, 11).bulk_modulus_scale, a.bulk_modulus_scale);
}

TEST(Uncertainty, ApplyVariationScalesTheJointModel) {
  JointPlantModel nominal;
  nominal.joint = test::dtsPlant().joints[3];
  nominal.load.inertia_kgm2 = 0.21;
  nominal.load.user_inertia_kgm2 = 0.06;
  nominal.load.gravity_cos_nm = 4.0;
  nominal.load.gravity_sin_nm = -1.5;
  nominal.load.user_stiffness_nm_per_rad = 25.0;
  nominal.load.user_damping_nms_per_rad = 8.3;
  ModelVariation v;
  v.bulk_modulus_scale = 0.7;
  v.valve_gain_scale = 1.1;
  v.friction_scale = 2.0;
  v.inertia_scale = 1.25;
  v.user_stiffness_nm_per_rad = 33.0;
  v.user_damping_nms_per_rad = 4.0;
  v.delay_samples = 3;
  const JointPlantModel m = applyVariation(nominal, v);
  EXPECT_DOUBLE_EQ(m.joint.fluid.oil_bulk_modulus_pa, 0.7 * nominal.joint.fluid.oil_bulk_modulus_pa);
  EXPECT_DOUBLE_EQ(m.joint.valve.rated_flow_m3ps, 1.1 * nominal.joint.valve.rated_flow_m3ps);
  EXPECT_DOUBLE_EQ(m.joint.friction.coulomb_nm, 2.0 * nominal.joint.friction.coulomb_nm);
  EXPECT_DOUBLE_EQ(m.joint.friction.static_nm, 2.0 * nominal.joint.friction.static_nm);
  EXPECT_DOUBLE_EQ(m.joint.friction.viscous_nms_per_rad, 2.0 * nominal.joint.friction.viscous_nms_per_rad);
  // Link and user inertia about the joint both scale; the actuator's own inertia does not.
  EXPECT_DOUBLE_EQ(m.load.inertia_kgm2, 1.25 * 0.21);
  EXPECT_DOUBLE_EQ(m.load.user_inertia_kgm2, 1.25 * 0.06);
  EXPECT_EQ(m.joint.actuator.inertia_kgm2, nominal.joint.actuator.inertia_kgm2);
  EXPECT_EQ(m.load.gravity_cos_nm, 4.0);
  EXPECT_EQ(m.load.gravity_sin_nm, -1.5);
  EXPECT_EQ(m.load.user_stiffness_nm_per_rad, 33.0);
  EXPECT_EQ(m.load.user_damping_nms_per_rad, 4.0);
  EXPECT_EQ(m.include_user, nominal.include_user);
}

// The scenario of a variation (the nonlinear runs) is the varied joint model (the linear analysis)
// written back: the same hydraulics, the same link and user inertia, the same user; each value
// against its own scaling of the nominal scenario, computed here by hand.
TEST(Uncertainty, TheScenarioOfAVariationIsItsJointModel) {
  const JointScenario nominal = makeJointScenario(test::dtsModel(), test::dtsPlant(), test::dtsGains(), "EB");
  ASSERT_GT(nominal.user.inertia_kgm2, 0.0);
  ModelVariation v;
  v.index = 7;
  v.bulk_modulus_scale = 0.7;
  v.valve_gain_scale = 1.1;
  v.friction_scale = 2.0;
  v.inertia_scale = 1.25;
  v.user_stiffness_nm_per_rad = 33.0;
  v.user_damping_nms_per_rad = 4.0;
  v.delay_samples = 3;
  const JointScenario sc = variationScenario(nominal, v);
  EXPECT_DOUBLE_EQ(sc.joint.fluid.oil_bulk_modulus_pa, 0.7 * nominal.joint.fluid.oil_bulk_modulus_pa);
  EXPECT_DOUBLE_EQ(sc.joint.valve.rated_flow_m3ps, 1.1 * nominal.joint.valve.rated_flow_m3ps);
  EXPECT_DOUBLE_EQ(sc.joint.friction.coulomb_nm, 2.0 * nominal.joint.friction.coulomb_nm);
  EXPECT_DOUBLE_EQ(sc.joint.friction.static_nm, 2.0 * nominal.joint.friction.static_nm);
  EXPECT_DOUBLE_EQ(sc.joint.friction.viscous_nms_per_rad, 2.0 * nominal.joint.friction.viscous_nms_per_rad);
  EXPECT_EQ(sc.joint.actuator.inertia_kgm2, nominal.joint.actuator.inertia_kgm2);
  // The scenario's load carries link + user inertia: both scaled, so the whole load is.
  EXPECT_DOUBLE_EQ(sc.load.inertia_kgm2, 1.25 * nominal.load.inertia_kgm2);
  EXPECT_DOUBLE_EQ(sc.user.inertia_kgm2, 1.25 * nominal.user.inertia_kgm2);
  EXPECT_EQ(sc.load.gravity_cos_nm, nominal.load.gravity_cos_nm);
  EXPECT_EQ(sc.expected_gravity_cos_nm, nominal.expected_gravity_cos_nm);
  EXPECT_EQ(sc.user.stiffness_nm_per_rad, 33.0);
  EXPECT_EQ(sc.user.damping_nms_per_rad, 4.0);
  EXPECT_EQ(sc.delay_samples, 3);
  EXPECT_EQ(sc.noise_seed, nominal.noise_seed + 1000003ULL * 8);
  EXPECT_NO_THROW(plant::validateJointParams(sc.joint));
  // Read back as a joint model, it is the varied joint model of the linear analysis.
  const JointPlantModel linear = applyVariation(scenarioPlantModel(nominal), v);
  const JointPlantModel back = scenarioPlantModel(sc);
  EXPECT_DOUBLE_EQ(back.load.inertia_kgm2, linear.load.inertia_kgm2);
  EXPECT_DOUBLE_EQ(back.load.user_inertia_kgm2, linear.load.user_inertia_kgm2);
  EXPECT_EQ(back.load.user_stiffness_nm_per_rad, linear.load.user_stiffness_nm_per_rad);
  EXPECT_EQ(back.load.user_damping_nms_per_rad, linear.load.user_damping_nms_per_rad);
  EXPECT_EQ(back.joint.fluid.oil_bulk_modulus_pa, linear.joint.fluid.oil_bulk_modulus_pa);
  EXPECT_EQ(back.joint.friction.coulomb_nm, linear.joint.friction.coulomb_nm);
}

}  // namespace
}  // namespace fullarm::design
