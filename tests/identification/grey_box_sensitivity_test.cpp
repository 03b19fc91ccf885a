// Forward sensitivities of the grey-box simulation (angle, load cell and hydraulic torque) against
// central differences of the simulation itself (an independent derivative of the same discretised map), at several
// parameter points: the valve's orifice law with its laps and rounding, the spool and load-cell filter, an initial
// state off rest, and a load near the stall torque.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "fullarm/identification/excitation.hpp"
#include "fullarm/identification/grey_box.hpp"

namespace fullarm::identification {
namespace {

constexpr double kT = 1.0e-3;

GreyModel base() {
  GreyModel m;
  m.value = {0.4, 8.0e3, 5.0e-4, 0.06, 0.8, 0.6, 0.4, 4.0, 0.01, 0.002, -0.3};
  m.delay_samples = 2;
  m.stall_torque_nm = 250.0;
  m.underlap_v = 0.04;
  m.edge_rounding_v = 0.02;
  m.load_gradient_nm_per_rad = 5.0;
  return m;
}

ExperimentData experiment(const GreyModel& truth) {
  ExperimentData d;
  d.excitation_v = prbs(1.5, 8, 3, 1, kT).value_v;  // 0.77 s
  d.hold_gain_v_per_rad = 10.0;
  d.hold_rad = 0.1;
  d.q_rad.assign(d.excitation_v.size(), 0.1);
  d.tau_nm.assign(d.excitation_v.size(), 0.0);
  const Simulation s = simulateClosedLoop(truth, d);
  d.q_rad = s.q_rad;
  d.tau_nm = s.tau_nm;
  d.command_v = s.command_v;
  return d;
}

double& member(GreyModel& m, InitialState& x, int direction) {
  if (direction == kInitialSpeed) return x.speed_radps;
  if (direction == kInitialTorqueOffset) return x.torque_offset_nm;
  return m.value[static_cast<std::size_t>(direction)];
}

std::string name(int direction) {
  return direction < kGreyParams ? greyParamName(direction) : initialStateName(direction);
}

// Every direction's sensitivity matches the central difference of the simulation to `rel` of the
// column's largest entry, and the values are the plain simulation's, bit for bit.
void expectMatchesCentralDifferences(const GreyModel& model, const ExperimentData& data, const InitialState& initial,
                                     double rel, const std::string& label) {
  std::vector<int> directions;
  for (int i = 0; i < kGreyParams; ++i) directions.push_back(i);
  directions.push_back(kInitialSpeed);
  directions.push_back(kInitialTorqueOffset);
  const SimulationSensitivity s = simulateSensitivities(model, data, initial, directions);
  const Simulation plain = simulateClosedLoop(model, data, initial);
  ASSERT_TRUE(s.simulation.ok) << label;
  EXPECT_EQ(s.simulation.q_rad, plain.q_rad) << label;
  EXPECT_EQ(s.simulation.tau_nm, plain.tau_nm) << label;
  EXPECT_EQ(s.simulation.tau_hydraulic_nm, plain.tau_hydraulic_nm) << label;
  for (std::size_t j = 0; j < directions.size(); ++j) {
    const int dir = directions[j];
    GreyModel up = model, down = model;
    InitialState iu = initial, id = initial;
    const double v = member(up, iu, dir);
    // A step of 1e-7 of the value or of the direction's typical size: the truncation error falls
    // as h^2 (at 1e-5 it still reaches 0.4 % on the torque's derivative by the inertia and the
    // leakage, at 1e-6 4e-5, at 1e-7 below the tolerance), the rounding (1e-16 of the outputs
    // over h) stays below it too.
    const double typical = dir == kInitialSpeed ? 0.1 : (dir == kAngleOffset || dir == kValveOffset) ? 0.01 : 1.0;
    const double h = 1e-7 * std::max(std::abs(v), typical);
    member(up, iu, dir) += h;
    member(down, id, dir) -= h;
    const Simulation a = simulateClosedLoop(up, data, iu);
    const Simulation b = simulateClosedLoop(down, data, id);
    ASSERT_TRUE(a.ok && b.ok) << label << ": " << name(dir);
    const auto col = static_cast<Eigen::Index>(j);
    const double q_scale = s.q_rad.col(col).cwiseAbs().maxCoeff();
    const double tau_scale = s.tau_nm.col(col).cwiseAbs().maxCoeff();
    if (dir == kAngleOffset) {
      // The offset shifts the start and the reading alike: the closed loop does not see it.
      EXPECT_EQ(q_scale + tau_scale, 0.0) << label;
    } else {
      EXPECT_GT(q_scale + tau_scale, 0.0) << label << ": " << name(dir) << " has no effect";
    }
    const double hydraulic_scale = s.tau_hydraulic_nm.col(col).cwiseAbs().maxCoeff();
    double q_err = 0.0, tau_err = 0.0, hydraulic_err = 0.0;
    for (std::size_t k = 0; k < data.q_rad.size(); ++k) {
      const auto row = static_cast<Eigen::Index>(k);
      q_err = std::max(q_err, std::abs((a.q_rad[k] - b.q_rad[k]) / (2.0 * h) - s.q_rad(row, col)));
      tau_err = std::max(tau_err, std::abs((a.tau_nm[k] - b.tau_nm[k]) / (2.0 * h) - s.tau_nm(row, col)));
      hydraulic_err = std::max(hydraulic_err, std::abs((a.tau_hydraulic_nm[k] - b.tau_hydraulic_nm[k]) / (2.0 * h) -
                                                       s.tau_hydraulic_nm(row, col)));
    }
    // Rounding of the differences: 1e-16 of outputs of order 1 rad and 100 N m over 2 h.
    EXPECT_LE(q_err, rel * q_scale + 1e-14 / h)
        << label << ": d angle / d " << name(dir) << " (scale " << q_scale << ")";
    EXPECT_LE(tau_err, rel * tau_scale + 1e-12 / h)
        << label << ": d torque / d " << name(dir) << " (scale " << tau_scale << ")";
    EXPECT_LE(hydraulic_err, rel * hydraulic_scale + 1e-12 / h)
        << label << ": d hydraulic torque / d " << name(dir) << " (scale " << hydraulic_scale << ")";
  }
}

TEST(GreyBoxSensitivityTest, MatchesCentralDifferencesWithTheOrificeLaw) {
  const GreyModel m = base();
  expectMatchesCentralDifferences(m, experiment(m), {}, 1e-5, "orifice law at rest");
}

TEST(GreyBoxSensitivityTest, MatchesCentralDifferencesAwayFromTheData) {
  GreyModel truth = base();
  const ExperimentData data = experiment(truth);
  GreyModel m = truth;
  m.value[kFlowGain] *= 1.7;
  m.value[kStiffness] /= 2.0;
  m.value[kInertia] *= 1.4;
  m.value[kLeakage] *= 3.0;
  m.delay_samples = 0;
  expectMatchesCentralDifferences(m, data, {0.3, -2.0}, 1e-5, "off the truth, moving start");
}

TEST(GreyBoxSensitivityTest, MatchesCentralDifferencesThroughSpoolAndLoadCellFilter) {
  GreyModel m = base();
  m.spool_hz = 150.0;
  m.spool_damping = 0.7;
  m.torque_filter_hz = 200.0;
  expectMatchesCentralDifferences(m, experiment(m), {-0.2, 1.5}, 1e-5, "spool and filter");
}

TEST(GreyBoxSensitivityTest, MatchesCentralDifferencesWithALinearisedValveUnderHeavyLoad) {
  GreyModel m = base();
  m.stall_torque_nm = 0.0;
  m.underlap_v = 0.0;
  m.edge_rounding_v = 0.0;
  m.value[kLoadTorque] = 40.0;
  expectMatchesCentralDifferences(m, experiment(m), {}, 1e-5, "linearised valve");
}

TEST(GreyBoxSensitivityTest, ADirectionThatIsNoParameterIsRefused) {
  const GreyModel m = base();
  const ExperimentData d = experiment(m);
  EXPECT_THROW((void)simulateSensitivities(m, d, {}, {kInitialTorqueOffset + 1}), std::invalid_argument);
  EXPECT_THROW((void)simulateSensitivities(m, d, {}, {-1}), std::invalid_argument);
}

}  // namespace
}  // namespace fullarm::identification
