// Full-amplitude 0.5-80 Hz chirps on every joint of the default DTS plant: pressures stay in
// [return, supply], the hard stops hold, and the response does not depend on the tolerance.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "fullarm/plant/signals.hpp"
#include "plant_fixture.hpp"
#include "plant_test_util.hpp"

namespace fullarm::plant {
namespace {

using test::PlantTolerance;

// Check valves bound the pressures up to the flow they must pass: 0.5 MPa is 2.4 % of supply.
constexpr double kPressureMargin_pa = 0.5e6;

struct ChirpRun {
  std::vector<double> q, p_load;
  double p_min = 1e300, p_max = -1e300, overshoot_rad = 0.0;
};

// Starts `start_from_limit_rad` inside the upper limit (0: the default posture).
ChirpRun runChirp(const JointParams& joint, const SolverOptions& options, double duration_s,
                  double start_from_limit_rad = 0.0) {
  const arm::ArmModel& model = test::dtsModel();
  Eigen::VectorXd posture = model.defaultPosture();
  if (start_from_limit_rad > 0.0) posture[model.jointIndex(joint.name)] = joint.max_rad - start_from_limit_rad;
  ArmPlant plant;
  plant.configure(model, {joint}, posture, UserArmParams{}, options, 1);
  SignalParams s;
  s.kind = SignalKind::kChirp;
  s.amplitude = 1.0 / joint.valve.amplifier_gain_per_v;  // full valve opening
  s.start_hz = 0.5;
  s.stop_hz = 80.0;
  s.duration_s = duration_s;
  PlantCommand cmd = PlantCommand::zero(1);
  ChirpRun r;
  const int periods = static_cast<int>(duration_s * 1000.0);
  for (int k = 0; k < periods; ++k) {
    cmd.command[0] = signalValue(s, k * 1e-3);
    EXPECT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
    const JointState st = plant.state(0);
    r.q.push_back(st.q_rad);
    r.p_load.push_back(st.p_a_pa - st.p_b_pa);
    r.p_min = std::min({r.p_min, st.p_a_pa, st.p_b_pa});
    r.p_max = std::max({r.p_max, st.p_a_pa, st.p_b_pa});
    r.overshoot_rad = std::max({r.overshoot_rad, st.q_rad - joint.max_rad, joint.min_rad - st.q_rad});
  }
  return r;
}

// The chirp checks run with each integrator: CVODES (the reference), Rodas3 and Rodas4.
class PlantChirp : public ::testing::TestWithParam<IntegratorKind> {
 protected:
  [[nodiscard]] SolverOptions options() const {
    SolverOptions o = test::dtsPlant().solver;
    o.integrator = GetParam();
    return o;
  }
};

TEST_P(PlantChirp, PressuresStayWithinSupplyAndReturnAndStopsHold) {
  const PlantConfig& config = test::dtsPlant();
  int joints_at_stop = 0;
  for (const JointParams& joint : config.joints) {
    const ChirpRun r = runChirp(joint, options(), 4.0, 0.1);
    EXPECT_GE(r.p_min, joint.return_pressure_pa - kPressureMargin_pa) << joint.name;
    EXPECT_LE(r.p_max, joint.supply_pressure_pa + kPressureMargin_pa) << joint.name;
    EXPECT_LE(r.overshoot_rad * 180.0 / std::numbers::pi, PlantTolerance::kStopOvershootDeg) << joint.name;
    // The chirp loads the chambers to near supply and return (the bounds are not vacuous).
    EXPECT_GT(r.p_max - r.p_min, 0.3 * (joint.supply_pressure_pa - joint.return_pressure_pa)) << joint.name;
    if (r.overshoot_rad > 0.0) ++joints_at_stop;
  }
  // Started 0.1 rad inside the upper limit, the first half wave drives every joint into the stop.
  EXPECT_EQ(joints_at_stop, static_cast<int>(config.joints.size()));
}

TEST_P(PlantChirp, ResponseIsIndependentOfSolverTolerance) {
  const PlantConfig& config = test::dtsPlant();
  const JointParams& joint = config.joints[static_cast<std::size_t>(findPlantJoint(config, "EB"))];
  SolverOptions half = options();
  half.rtol *= 0.5;
  const ChirpRun a = runChirp(joint, options(), 4.0);
  const ChirpRun b = runChirp(joint, half, 4.0);
  EXPECT_LT(normalisedRmsDifference(a.q, b.q), PlantTolerance::kRtolHalvingRms);
  EXPECT_LT(normalisedRmsDifference(a.p_load, b.p_load), PlantTolerance::kRtolHalvingRms);
  // ... and the comparison is not vacuous: a tenfold looser rtol is visibly different.
  SolverOptions loose = options();
  loose.rtol *= 100.0;
  loose.atol_pressure_pa *= 100.0;
  loose.atol_angle_rad *= 100.0;
  const ChirpRun c = runChirp(joint, loose, 4.0);
  EXPECT_GT(normalisedRmsDifference(a.p_load, c.p_load), 1e-5);
}

INSTANTIATE_TEST_SUITE_P(Integrators, PlantChirp,
                         ::testing::Values(IntegratorKind::kCvodes, IntegratorKind::kRodas3, IntegratorKind::kRodas4,
                                           IntegratorKind::kRos34pw2),
                         [](const ::testing::TestParamInfo<IntegratorKind>& param_info) {
                           return param_info.param == IntegratorKind::kCvodes   ? "Cvodes"
                                  : param_info.param == IntegratorKind::kRodas3 ? "Rodas3"
                                  : param_info.param == IntegratorKind::kRodas4 ? "Rodas4"
                                                                                : "Ros34pw2";
                         });

// Rodas3 and Rodas4 at the configured tolerances against the tight CVODES reference on the EB chirp, from
// the default posture and from 0.1 rad inside the upper limit (stop contacts): within the same
// 0.5 % RMS allowed between rtol and rtol/2, for the angle and the load pressure.
TEST(PlantIntegrators, Rodas3MatchesTightCvodesReferenceOnJointChirp) {
  const PlantConfig& config = test::dtsPlant();
  const JointParams& joint = config.joints[static_cast<std::size_t>(findPlantJoint(config, "EB"))];
  for (const double from_limit : {0.0, 0.1}) {
    const ChirpRun ref = runChirp(joint, tightReferenceOptions(test::dtsPlant().solver), 4.0, from_limit);
    for (const IntegratorKind integrator :
         {IntegratorKind::kRodas3, IntegratorKind::kRodas4, IntegratorKind::kRos34pw2}) {
      SolverOptions rodas = config.solver;
      rodas.integrator = integrator;
      const ChirpRun r = runChirp(joint, rodas, 4.0, from_limit);
      const char* name = integrator == IntegratorKind::kRodas3   ? "Rodas3"
                         : integrator == IntegratorKind::kRodas4 ? "Rodas4"
                                                                 : "ROS34PW2";
      EXPECT_LT(normalisedRmsDifference(ref.q, r.q), PlantTolerance::kRtolHalvingRms)
          << name << " from limit " << from_limit;
      EXPECT_LT(normalisedRmsDifference(ref.p_load, r.p_load), PlantTolerance::kRtolHalvingRms)
          << name << " from limit " << from_limit;
    }
  }
}

// The same on the whole arm (all seven joints chirped at once, 1 s), per joint, from the default
// posture and from 0.1 rad inside every upper limit (stop contacts on every joint).
TEST(PlantIntegrators, Rodas3MatchesTightCvodesReferenceOnArmChirp) {
  const arm::ArmModel& model = test::dtsModel();
  const PlantConfig& config = test::dtsPlant();
  auto run = [&](const SolverOptions& options, double from_limit_rad) {
    Eigen::VectorXd posture = model.defaultPosture();
    if (from_limit_rad > 0.0) {
      for (const JointParams& j : config.joints) posture[model.jointIndex(j.name)] = j.max_rad - from_limit_rad;
    }
    ArmPlant plant;
    plant.configure(model, config.joints, posture, UserArmParams{}, options, 1);
    const int n = plant.numJoints();
    SignalParams s;
    s.kind = SignalKind::kChirp;
    s.amplitude = 1.0 / config.joints[0].valve.amplifier_gain_per_v;
    s.start_hz = 0.5;
    s.stop_hz = 80.0;
    s.duration_s = 1.0;
    PlantCommand cmd = PlantCommand::zero(n);
    std::vector<ChirpRun> runs(static_cast<std::size_t>(n));
    for (int k = 0; k < 1000; ++k) {
      for (int j = 0; j < n; ++j) cmd.command[j] = signalValue(s, k * 1e-3);
      EXPECT_TRUE(plant.step(1e-3, cmd).ok()) << plant.lastError();
      for (int j = 0; j < n; ++j) {
        const JointState st = plant.state(j);
        runs[static_cast<std::size_t>(j)].q.push_back(st.q_rad);
        runs[static_cast<std::size_t>(j)].p_load.push_back(st.p_a_pa - st.p_b_pa);
      }
    }
    return runs;
  };
  for (const double from_limit : {0.0, 0.1}) {
    const std::vector<ChirpRun> ref = run(tightReferenceOptions(test::dtsPlant().solver), from_limit);
    for (const int variant : {0, 1, 2, 3}) {
      // Rodas3, Rodas4, Rodas3 with the rigid-body derivatives once per period, ROS34PW2 (Jacobian once per period)
      SolverOptions rodas = config.solver;
      rodas.integrator = variant == 1   ? IntegratorKind::kRodas4
                         : variant == 3 ? IntegratorKind::kRos34pw2
                                        : IntegratorKind::kRodas3;
      rodas.rigid_derivatives_once_per_period = variant == 2;
      const std::vector<ChirpRun> r = run(rodas, from_limit);
      const char* name = variant == 0   ? "Rodas3"
                         : variant == 1 ? "Rodas4"
                         : variant == 2 ? "Rodas3 rigid once per period"
                                        : "ROS34PW2";
      for (std::size_t j = 0; j < ref.size(); ++j) {
        EXPECT_LT(normalisedRmsDifference(ref[j].q, r[j].q), 2.0 * PlantTolerance::kRtolHalvingRms)
            << name << " " << config.joints[j].name << " from limit " << from_limit;
        EXPECT_LT(normalisedRmsDifference(ref[j].p_load, r[j].p_load), 2.0 * PlantTolerance::kRtolHalvingRms)
            << name << " " << config.joints[j].name << " from limit " << from_limit;
      }
    }
  }
}

}  // namespace
}  // namespace fullarm::plant
