// A plant run (plant::simulate, makeCommand, writeTraceCsv): the trace's time base and length, the
// outputs against a hand-written loop of ArmPlant::step calls, the generated commands against the
// signal formulas, command-table columns by joint name, and the CSV written and read back.

#include "fullarm/plant/simulation.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "fullarm/plant/signals.hpp"
#include "plant_fixture.hpp"
#include "scratch_dir.hpp"

namespace fullarm::plant {
namespace {

using test::dtsModel;
using test::dtsPlant;

constexpr double kDt_s = 1e-3;
// writeTraceCsv prints 10 significant digits: a value read back is within half a unit of the
// tenth digit.
constexpr double kCsvRelative = 5e-10;

JointParams dtsJoint(const std::string& name) {
  return dtsPlant().joints[static_cast<std::size_t>(findPlantJoint(dtsPlant(), name))];
}

InputSignal chirp(double amplitude) {
  InputSignal input;
  input.name = "chirp";
  input.amplitude = amplitude;
  input.start_hz = 0.5;
  input.stop_hz = 80.0;
  return input;
}

std::vector<double> parseRow(const std::string& line) {
  std::vector<double> values;
  std::stringstream row(line);
  std::string cell;
  while (std::getline(row, cell, ',')) values.push_back(std::strtod(cell.c_str(), nullptr));
  return values;
}

TEST(PlantSimulation, TraceHoldsOneSamplePerPeriodBoundaryOnTheControlTimeBase) {
  const std::vector<JointParams> joints = {dtsJoint("EB")};
  const double duration_s = 0.05;
  const SimulationResult r = simulate(dtsModel(), dtsPlant(), joints,
                                      makeCommand(chirp(1.0), dtsModel(), joints, duration_s), duration_s, kDt_s);
  ASSERT_TRUE(r.solver_ok) << r.solver_error;
  ASSERT_EQ(r.traces.size(), 1u);
  const JointTrace& tr = r.traces[0];
  EXPECT_EQ(tr.joint, "R_EB");
  // t_0 = 0 to t_N = duration: N + 1 samples.
  ASSERT_EQ(tr.time_s.size(), 51u);
  for (const auto* column :
       {&tr.command, &tr.q_rad, &tr.qd_radps, &tr.tau_measured_nm, &tr.p_a_pa, &tr.p_b_pa, &tr.spool_fraction}) {
    EXPECT_EQ(column->size(), tr.time_s.size());
  }
  for (std::size_t i = 0; i < tr.time_s.size(); ++i) EXPECT_EQ(tr.time_s[i], static_cast<double>(i) * kDt_s);
  EXPECT_NEAR(r.simulated_s, duration_s, 1e-12);
  EXPECT_GT(r.stats.steps, 0);
  EXPECT_TRUE(r.pressures_ok);
  EXPECT_TRUE(r.stops_held);
  EXPECT_TRUE(r.passed());
  EXPECT_EQ(tr.command_unit, CommandUnit::kVolt);
  // In torque-loop mode the command is a torque.
  std::vector<JointParams> torque_joints = joints;
  torque_joints[0].input_mode = InputMode::kTorqueLoop;
  const SimulationResult t = simulate(dtsModel(), dtsPlant(), torque_joints,
                                      makeCommand(chirp(1.0), dtsModel(), torque_joints, 0.01), 0.01, kDt_s);
  EXPECT_EQ(t.traces[0].command_unit, CommandUnit::kNewtonMetre);
}

TEST(PlantSimulation, OutputsEqualAHandWrittenLoopOfArmPlantSteps) {
  const arm::ArmModel& model = dtsModel();
  const PlantConfig& config = dtsPlant();
  const std::vector<JointParams> joints = config.joints;  // the whole arm
  const double duration_s = 0.02;
  const CommandFunction command = makeCommand(chirp(2.0), model, joints, duration_s);
  const SimulationResult r = simulate(model, config, joints, command, duration_s, kDt_s);
  ASSERT_TRUE(r.solver_ok) << r.solver_error;

  ArmPlant plant;
  plant.configure(model, joints, model.defaultPosture(), config.user_arm, config.solver, config.seed);
  const int n = plant.numJoints();
  ASSERT_EQ(r.traces.size(), static_cast<std::size_t>(n));
  PlantCommand cmd = PlantCommand::zero(n);
  const int periods = 20;
  for (int i = 0; i <= periods; ++i) {
    const double t = i * kDt_s;
    for (int k = 0; k < n; ++k) cmd.command[k] = command(static_cast<std::size_t>(k), t);
    for (int k = 0; k < n; ++k) {
      const JointTrace& tr = r.traces[static_cast<std::size_t>(k)];
      const auto s = static_cast<std::size_t>(i);
      const JointState state = plant.state(k);
      ASSERT_LT(s, tr.time_s.size());
      EXPECT_EQ(tr.joint, plant.joint(k).name);
      EXPECT_EQ(tr.command[s], cmd.command[k]) << k << " " << i;
      EXPECT_EQ(tr.q_rad[s], state.q_rad) << k << " " << i;
      EXPECT_EQ(tr.qd_radps[s], state.qd_radps) << k << " " << i;
      EXPECT_EQ(tr.tau_measured_nm[s], plant.measurement(k).tau_nm) << k << " " << i;
      EXPECT_EQ(tr.p_a_pa[s], state.p_a_pa) << k << " " << i;
      EXPECT_EQ(tr.p_b_pa[s], state.p_b_pa) << k << " " << i;
      EXPECT_EQ(tr.spool_fraction[s], state.spool) << k << " " << i;
    }
    if (i < periods) {
      ASSERT_TRUE(plant.step(kDt_s, cmd).ok());
    }
  }
  for (const JointTrace& tr : r.traces) EXPECT_EQ(tr.time_s.size(), static_cast<std::size_t>(periods + 1));
  EXPECT_EQ(r.simulated_s, plant.time());
  EXPECT_EQ(r.stats.steps, plant.stats().steps);
  EXPECT_EQ(r.stats.rhs_evals, plant.stats().rhs_evals);
  EXPECT_EQ(r.stats.jac_evals, plant.stats().jac_evals);
  EXPECT_EQ(r.stats.reinits, plant.stats().reinits);
}

TEST(PlantSimulation, GeneratedCommandsFollowTheSignalFormulasWithFullScaleByDefault) {
  const arm::ArmModel& model = dtsModel();
  const JointParams eb = dtsJoint("EB");
  JointParams eb_torque = eb;
  eb_torque.input_mode = InputMode::kTorqueLoop;
  const std::vector<JointParams> joints = {eb, eb_torque};
  EXPECT_EQ(commandUnit(eb), CommandUnit::kVolt);
  EXPECT_EQ(commandUnit(eb_torque), CommandUnit::kNewtonMetre);
  JointParams ideal = eb;
  ideal.actuator.kind = ActuatorKind::kIdealTorque;
  EXPECT_EQ(commandUnit(ideal), CommandUnit::kNewtonMetre);
  // Full scale: 1 / amplifier gain volts in valve mode, the torque limit in torque-loop mode.
  EXPECT_EQ(fullScaleCommand(eb, model), 1.0 / eb.valve.amplifier_gain_per_v);
  EXPECT_EQ(fullScaleCommand(eb_torque, model),
            model.joints[static_cast<std::size_t>(model.jointIndex("R_EB"))].limits.torque_nm);

  // Chirp: A sin(2 pi (f0 t + (f1 - f0) t^2 / (2 T))), T the run's duration.
  const CommandFunction c = makeCommand(chirp(2.0), model, joints, 2.0);
  for (const double t : {0.01, 0.13, 0.77, 1.9}) {
    EXPECT_NEAR(c(0, t), 2.0 * std::sin(2.0 * std::numbers::pi * (0.5 * t + (80.0 - 0.5) * t * t / (2.0 * 2.0))), 1e-9);
  }
  InputSignal sine;
  sine.name = "sine";
  sine.frequency_hz = 3.0;
  const CommandFunction u = makeCommand(sine, model, joints, 2.0);
  for (const double t : {0.01, 0.13, 0.77}) {
    EXPECT_NEAR(u(0, t), fullScaleCommand(eb, model) * std::sin(2.0 * std::numbers::pi * 3.0 * t), 1e-12);
    EXPECT_NEAR(u(1, t), fullScaleCommand(eb_torque, model) * std::sin(2.0 * std::numbers::pi * 3.0 * t), 1e-9);
  }
  // A step rises at min(0.1 s, duration / 10).
  InputSignal step;
  step.name = "step";
  step.amplitude = 2.5;
  const CommandFunction short_step = makeCommand(step, model, joints, 0.5);
  EXPECT_EQ(short_step(0, 0.049), 0.0);
  EXPECT_EQ(short_step(0, 0.051), 2.5);
  const CommandFunction long_step = makeCommand(step, model, joints, 5.0);
  EXPECT_EQ(long_step(0, 0.099), 0.0);
  EXPECT_EQ(long_step(0, 0.101), 2.5);

  InputSignal inverted = chirp(1.0);
  inverted.stop_hz = inverted.start_hz;
  EXPECT_THROW((void)makeCommand(inverted, model, joints, 1.0), std::invalid_argument);
  InputSignal unknown;
  unknown.name = "square";
  EXPECT_THROW((void)makeCommand(unknown, model, joints, 1.0), std::invalid_argument);
}

TEST(PlantSimulation, CommandTableDrivesEachJointWithItsColumn) {
  const std::filesystem::path dir = fullarm::test::scratchDir("plant_simulation_table");
  const std::filesystem::path file = dir / "commands.csv";
  std::ofstream(file) << "time_s,command,command_EB,command_R_WR\n0,1,2,3\n0.5,4,5,6\n";
  const std::vector<JointParams> joints = {dtsJoint("SFE"), dtsJoint("EB"), dtsJoint("WR")};
  InputSignal table;
  table.name = file.string();
  const CommandFunction u = makeCommand(table, dtsModel(), joints, 1.0);
  // SFE has no column of its own: the first one. EB by short name, WR by model name; held between rows.
  EXPECT_EQ(u(0, 0.2), 1.0);
  EXPECT_EQ(u(1, 0.2), 2.0);
  EXPECT_EQ(u(2, 0.2), 3.0);
  EXPECT_EQ(u(0, 0.7), 4.0);
  EXPECT_EQ(u(1, 0.7), 5.0);
  EXPECT_EQ(u(2, 0.7), 6.0);
  std::filesystem::remove_all(dir);
}

TEST(PlantSimulation, CsvHasTheDocumentedHeaderAndReadsBackToTheTrace) {
  const std::vector<JointParams> joints = {dtsJoint("EB")};
  const double duration_s = 0.03;
  const SimulationResult r = simulate(dtsModel(), dtsPlant(), joints,
                                      makeCommand(chirp(3.0), dtsModel(), joints, duration_s), duration_s, kDt_s);
  ASSERT_TRUE(r.solver_ok);
  const JointTrace& tr = r.traces[0];
  const std::filesystem::path dir = fullarm::test::scratchDir("plant_simulation_csv");
  writeTraceCsv(tr, dir / "trace.csv");
  std::ifstream in(dir / "trace.csv");
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(line, "time_s,command_v,q_rad,qd_rad_s,tau_measured_nm,p_a_pa,p_b_pa,spool_fraction");
  std::size_t rows = 0;
  const auto near = [](double read, double written) {
    return std::abs(read - written) <= kCsvRelative * std::abs(written) + 1e-300;
  };
  while (std::getline(in, line)) {
    const std::vector<double> v = parseRow(line);
    ASSERT_EQ(v.size(), 8u) << line;
    ASSERT_LT(rows, tr.time_s.size());
    const std::vector<double> expected = {tr.time_s[rows],   tr.command[rows],         tr.q_rad[rows],
                                          tr.qd_radps[rows], tr.tau_measured_nm[rows], tr.p_a_pa[rows],
                                          tr.p_b_pa[rows],   tr.spool_fraction[rows]};
    for (std::size_t c = 0; c < v.size(); ++c)
      EXPECT_PRED2(near, v[c], expected[c]) << "row " << rows << " column " << c;
    // No negative zero is written.
    EXPECT_EQ(line.find("-0,"), std::string::npos) << line;
    ++rows;
  }
  EXPECT_EQ(rows, tr.time_s.size());
  // A command in N m names its column so.
  JointTrace torque = tr;
  torque.command_unit = CommandUnit::kNewtonMetre;
  writeTraceCsv(torque, dir / "torque.csv");
  std::ifstream torque_in(dir / "torque.csv");
  ASSERT_TRUE(std::getline(torque_in, line));
  EXPECT_EQ(line, "time_s,command_nm,q_rad,qd_rad_s,tau_measured_nm,p_a_pa,p_b_pa,spool_fraction");
  EXPECT_THROW(writeTraceCsv(tr, dir / "missing" / "trace.csv"), std::runtime_error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace fullarm::plant
