// The gain tuner: against a brute-force scan on a one-variable problem, determinism, an
// infeasible specification, and the gains YAML round trip that `fullarm validate` relies on.

#include <gtest/gtest.h>

#include <cmath>

#include "design_fixture.hpp"
#include "fullarm/controllers/gains.hpp"
#include "fullarm/core/random.hpp"
#include "fullarm/design/tuner.hpp"

namespace fullarm::design {
namespace {

/// The tuner polishes with COBYLA (xtol_rel 1e-4 in log10 space): its optimum may sit this
/// much (relative) above the brute-force one.
constexpr double kOptimumRelative = 0.01;

struct Fixture {
  JointPlantModel model;
  double q_rad = 0.0;
  controllers::JointGains gains;
};

Fixture elbow() {
  const auto& m = test::dtsModel();
  const auto& cfg = test::dtsPlant();
  Fixture f;
  f.model.joint = cfg.joints[static_cast<std::size_t>(plant::findPlantJoint(cfg, "EB"))];
  const int idx = m.jointIndex(f.model.joint.name);
  f.model.load = jointLoadFromArm(m, plant::UserArmParams{}, idx, m.defaultPosture());
  f.model.load.user_inertia_kgm2 = 0.06;
  f.model.load.user_stiffness_nm_per_rad = 25.0;
  f.model.load.user_damping_nms_per_rad = 8.3;
  f.q_rad = m.defaultPosture()[idx];
  f.gains = test::dtsGains().joints[static_cast<std::size_t>(controllers::findGainsJoint(test::dtsGains(), "EB"))];
  return f;
}

TunerOptions smallBudget() {
  TunerOptions o;
  o.global_evaluations = 60;
  o.local_evaluations = 40;
  o.rounds = 1;
  o.grid_points = 60;
  return o;
}

TEST(Tuner, FindsTheBruteForceOptimumOfOneFreeVariable) {
  // Pin J_m, B_m, K_m and lambda; only B_o/eps is free. A dense scan of the same goals gives
  // the best feasible objective the tuner must reach.
  const Fixture f = elbow();
  TuningBounds b;
  const auto pin = [](double(&range)[2], double value) {
    range[0] = value;
    range[1] = value;
  };
  pin(b.inertia_kgm2, f.gains.impedance.inertia_kgm2);
  pin(b.damping_nms_per_rad, f.gains.impedance.damping_nms_per_rad);
  pin(b.stiffness_nm_per_rad, f.gains.impedance.stiffness_nm_per_rad);
  pin(b.lambda_per_s, f.gains.sliding_mode.lambda_per_s);
  // The search against a brute force, on the goals without the coupled grid (with it, no B_o/eps
  // of these pinned EB gains is feasible: the detector score of the slowest coupled mode stays
  // above 1; the coupled goal has its own oracles in coupled_stability_test.cpp).
  TuningGoals goals;
  goals.coupled_hard = false;
  const TunerOptions o = smallBudget();
  const LoopSetup setup;
  const TuningResult r = tuneJoint(f.model, f.q_rad, f.gains, setup, goals, b, UncertaintyRanges{}, o);
  ASSERT_TRUE(r.feasible) << r.verdict;
  // Brute force on the same single nominal model.
  LoopSetup s = setup;
  s.grid_points = o.grid_points;
  ModelVariation nominal;
  nominal.user_stiffness_nm_per_rad = f.model.load.user_stiffness_nm_per_rad;
  nominal.user_damping_nms_per_rad = f.model.load.user_damping_nms_per_rad;
  const std::vector<PreparedJoint> set = {prepareVariation(f.model, f.q_rad, s, nominal)};
  double best = std::numeric_limits<double>::infinity();
  const int n = 600;
  for (int i = 0; i <= n; ++i) {
    const double k =
        std::pow(10.0, std::log10(b.gain_v_s_per_rad[0]) +
                           (std::log10(b.gain_v_s_per_rad[1]) - std::log10(b.gain_v_s_per_rad[0])) * i / n);
    controllers::JointGains g = f.gains;
    g.sliding_mode.boundary_layer_radps = g.sliding_mode.valve_bound_v / k;
    const GoalValues v = evaluateGoals(set, g, goals);
    if (v.feasible()) best = std::min(best, v.soft);
  }
  ASSERT_TRUE(std::isfinite(best));
  EXPECT_LE(r.tuned_goals.soft, best * (1.0 + kOptimumRelative));
  EXPECT_TRUE(r.tuned_goals.feasible());
  // The tracked history ends at the returned point's objective.
  ASSERT_FALSE(r.history.empty());
  EXPECT_DOUBLE_EQ(r.history.back(), r.tuned_goals.soft);
}

TEST(Tuner, IsDeterministic) {
  const Fixture f = elbow();
  TunerOptions o = smallBudget();
  o.rounds = 2;
  o.worst_case_samples = 4;
  const TuningResult a =
      tuneJoint(f.model, f.q_rad, f.gains, LoopSetup{}, TuningGoals{}, TuningBounds{}, UncertaintyRanges{}, o);
  const TuningResult b =
      tuneJoint(f.model, f.q_rad, f.gains, LoopSetup{}, TuningGoals{}, TuningBounds{}, UncertaintyRanges{}, o);
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.tuned.impedance.inertia_kgm2, b.tuned.impedance.inertia_kgm2);
  EXPECT_EQ(a.tuned.impedance.damping_nms_per_rad, b.tuned.impedance.damping_nms_per_rad);
  EXPECT_EQ(a.tuned.impedance.stiffness_nm_per_rad, b.tuned.impedance.stiffness_nm_per_rad);
  EXPECT_EQ(a.tuned.sliding_mode.boundary_layer_radps, b.tuned.sliding_mode.boundary_layer_radps);
  EXPECT_EQ(a.tuned.sliding_mode.lambda_per_s, b.tuned.sliding_mode.lambda_per_s);
  ASSERT_EQ(a.model_set.size(), b.model_set.size());
  for (std::size_t i = 0; i < a.model_set.size(); ++i) {
    EXPECT_EQ(a.model_set[i].bulk_modulus_scale, b.model_set[i].bulk_modulus_scale);
    EXPECT_EQ(a.model_set[i].delay_samples, b.model_set[i].delay_samples);
  }
  EXPECT_EQ(a.nlopt_results, b.nlopt_results);
}

// The worst-case search draws its random models with the box's one sampler (uncertainty.hpp),
// from its own salted stream keyed by the joint's name: every model it adds is a corner of the box
// or a draw of that stream, recomputed here, and none is a draw of validate's stream.
TEST(Tuner, WorstCaseModelsAreCornersOrDrawsOfTheJointsOwnStream) {
  const Fixture f = elbow();
  TunerOptions o = smallBudget();
  o.rounds = 4;
  o.worst_case_samples = 6;
  const UncertaintyRanges ranges;
  const TuningResult r = tuneJoint(f.model, f.q_rad, f.gains, LoopSetup{}, TuningGoals{}, TuningBounds{}, ranges, o);
  ASSERT_GE(r.model_set.size(), 2u) << "no worst-case model was added: the test checks nothing";
  const auto same = [](const ModelVariation& a, const ModelVariation& b) {
    return a.bulk_modulus_scale == b.bulk_modulus_scale && a.valve_gain_scale == b.valve_gain_scale &&
           a.friction_scale == b.friction_scale && a.inertia_scale == b.inertia_scale &&
           a.user_stiffness_nm_per_rad == b.user_stiffness_nm_per_rad &&
           a.user_damping_nms_per_rad == b.user_damping_nms_per_rad && a.delay_samples == b.delay_samples;
  };
  const auto at_end = [](double x, const UniformRange& u) { return x == u.min || x == u.max; };
  int draws = 0;
  for (std::size_t m = 1; m < r.model_set.size(); ++m) {
    const ModelVariation& v = r.model_set[m];
    const bool corner = at_end(v.bulk_modulus_scale, ranges.bulk_modulus_scale) &&
                        at_end(v.valve_gain_scale, ranges.valve_gain_scale) &&
                        at_end(v.friction_scale, ranges.friction_scale) &&
                        at_end(v.inertia_scale, ranges.inertia_scale);
    if (corner) continue;
    bool found = false;
    for (int i = 0; i < o.rounds * o.worst_case_samples && !found; ++i) {
      found = same(v, drawVariation(ranges, o.seed ^ kWorstCaseSearchSalt, core::nameSlot(f.gains.name), i));
      EXPECT_FALSE(same(v, drawVariation(ranges, o.seed, core::nameSlot(f.gains.name), i))) << i;
    }
    EXPECT_TRUE(found) << "model " << m << " is neither a corner nor a draw of the joint's worst-case stream";
    draws += found ? 1 : 0;
  }
  EXPECT_GE(draws, 1) << "only corners were added: the stream is not checked";  // 2 of 3 at this budget
}

TEST(Tuner, InfeasibleSpecificationGetsAClearVerdict) {
  // Ms <= 0.5 would need |1 + L| >= 2 at every frequency, impossible where |L| is small.
  const Fixture f = elbow();
  TuningGoals goals;
  goals.max_peak_sensitivity = 0.5;
  const TuningResult r =
      tuneJoint(f.model, f.q_rad, f.gains, LoopSetup{}, goals, TuningBounds{}, UncertaintyRanges{}, smallBudget());
  EXPECT_FALSE(r.feasible);
  EXPECT_NE(r.verdict.find("infeasible"), std::string::npos) << r.verdict;
  // The hard-goal trace shows the search's progress: one entry per evaluation, never rising
  // within a round (rounds re-score on a larger set), above 1 throughout.
  ASSERT_EQ(r.hard_history.size(), r.history.size());
  ASSERT_FALSE(r.hard_history.empty());
  for (std::size_t i = 1; i < r.hard_history.size(); ++i) EXPECT_LE(r.hard_history[i], r.hard_history[i - 1]);
  EXPECT_GT(r.hard_history.back(), 1.0);
  EXPECT_NE(r.verdict.find("peak sensitivity"), std::string::npos) << r.verdict;
  // The starting gains are returned unchanged.
  EXPECT_EQ(r.tuned.impedance.inertia_kgm2, f.gains.impedance.inertia_kgm2);
  EXPECT_EQ(r.tuned.sliding_mode.boundary_layer_radps, f.gains.sliding_mode.boundary_layer_radps);
}

TEST(Tuner, TunedGainsRoundTripThroughTheGainsLoader) {
  const Fixture f = elbow();
  TuningGoals goals;
  goals.coupled_hard = false;  // a feasible EB point at this budget (see the brute-force test)
  const TuningResult r =
      tuneJoint(f.model, f.q_rad, f.gains, LoopSetup{}, goals, TuningBounds{}, UncertaintyRanges{}, smallBudget());
  ASSERT_TRUE(r.feasible) << r.verdict;
  controllers::GainsConfig config = test::dtsGains();
  config.joints[static_cast<std::size_t>(controllers::findGainsJoint(config, "EB"))] = r.tuned;
  const controllers::GainsConfig back =
      controllers::parseGainsConfig(controllers::formatGainsYaml(config), "tuned.yaml", test::dtsModel());
  const controllers::JointGains& g = back.joints[static_cast<std::size_t>(controllers::findGainsJoint(back, "EB"))];
  EXPECT_EQ(g.impedance.inertia_kgm2, r.tuned.impedance.inertia_kgm2);
  EXPECT_EQ(g.impedance.damping_nms_per_rad, r.tuned.impedance.damping_nms_per_rad);
  EXPECT_EQ(g.impedance.stiffness_nm_per_rad, r.tuned.impedance.stiffness_nm_per_rad);
  EXPECT_EQ(g.sliding_mode.lambda_per_s, r.tuned.sliding_mode.lambda_per_s);
  EXPECT_EQ(g.sliding_mode.valve_bound_v, r.tuned.sliding_mode.valve_bound_v);
  EXPECT_EQ(g.sliding_mode.boundary_layer_radps, r.tuned.sliding_mode.boundary_layer_radps);
}

TEST(Tuner, RejectsBadOptions) {
  const Fixture f = elbow();
  TunerOptions o = smallBudget();
  o.rounds = 0;
  EXPECT_THROW(
      (void)tuneJoint(f.model, f.q_rad, f.gains, LoopSetup{}, TuningGoals{}, TuningBounds{}, UncertaintyRanges{}, o),
      std::invalid_argument);
  TuningBounds b;
  b.lambda_per_s[0] = 10.0;
  b.lambda_per_s[1] = 1.0;
  EXPECT_THROW(
      (void)tuneJoint(f.model, f.q_rad, f.gains, LoopSetup{}, TuningGoals{}, b, UncertaintyRanges{}, smallBudget()),
      std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::design
