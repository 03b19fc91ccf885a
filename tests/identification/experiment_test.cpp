// The closed-loop experiment runner: against a scripted device whose joints integrate their
// valve commands: the log and the hold law recomputed independently (the simulated DTS
// is in experiment_sim_test.cpp).

#include "fullarm/identification/experiment.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace fullarm::identification {
namespace {

constexpr double kT = 1.0e-3;

/// Each joint's angle integrates its applied command less a constant load: q += gain * T * (u - load)
/// (one period of delay; a load makes a proportional hold droop by load / K).
class IntegratorDevice final : public hil::IoDevice {
 public:
  IntegratorDevice(int joints, double ramp_in_s)
      : hil::IoDevice(arm::JointSelection(joints,
                                          [joints] {
                                            std::vector<int> all;
                                            for (int k = 0; k < joints; ++k) all.push_back(k);
                                            return all;
                                          }()),
                      kT, hil::IoSafetyParams{ramp_in_s, 10.0}),
        q_(hil::IoVector::Constant(joints, 0.2)),
        held_(hil::IoVector::Zero(joints)) {}
  [[nodiscard]] std::string_view name() const noexcept override { return "integrator"; }
  /// Every joint at `q_rad` (before the first read).
  void startAt(double q_rad) { q_.setConstant(q_rad); }
  double gain_radps_per_v = 0.5;
  double load_v = 0.0;
  int reads = 0;
  int fail_read_at = -1;
  /// Every angle read and every command written to joint `recorded_joint`, in order (capacity
  /// reserved beforehand: recording does not allocate).
  int recorded_joint = 0;
  std::vector<double> read_q, written_u;

 private:
  void onConfigure() override {}
  core::RtStatus onRead(hil::JointSample& sample) noexcept override {
    if (reads++ == fail_read_at) return core::RtStatus::fault(core::RtCode::kBadInput, 0, "scripted read failure");
    q_ += gain_radps_per_v * kT * (held_.array() - load_v).matrix();
    t_ += kT;
    sample.t_s = t_;
    sample.q_rad = q_;
    sample.tau_load_cell_nm = 100.0 * held_;
    if (read_q.size() < read_q.capacity()) read_q.push_back(q_[recorded_joint]);
    return {};
  }
  core::RtStatus onWrite(const hil::IoVector& valve_v, bool) noexcept override {
    held_ = valve_v;
    if (written_u.size() < written_u.capacity()) written_u.push_back(valve_v[recorded_joint]);
    return {};
  }
  hil::IoVector q_;
  hil::IoVector held_;
  double t_ = 0.0;
};

TEST(ExperimentTest, LogsTheHoldLawPlusExcitationAlignedWithTheReadings) {
  IntegratorDevice device(3, 0.0);
  const SampledSignal r = linearChirp(0.5, 1.0, 20.0, 2.0, kT);
  ExperimentOptions options;
  options.joint = 1;
  options.settle_s = 0.1;
  const ExperimentResult result = runExperiment(device, r, options);
  ASSERT_TRUE(result.completed) << result.stop_reason;
  EXPECT_EQ(device.state(), hil::IoState::kInactive);
  ASSERT_EQ(result.log.rows(), r.value_v.size());
  ASSERT_EQ(result.hold_rad.size(), 3u);
  EXPECT_DOUBLE_EQ(result.hold_rad[1], 0.2);
  const auto& t = result.log.column("time_s");
  const auto& e = result.log.column("excitation_v");
  const auto& u = result.log.column("command_v");
  const auto& q = result.log.column("q_rad");
  const auto& tau = result.log.column("tau_measured_nm");
  for (std::size_t k = 0; k < r.value_v.size(); ++k) {
    ASSERT_EQ(e[k], r.value_v[k]);
    ASSERT_NEAR(u[k], options.hold_gain_v_per_rad * (0.2 - q[k]) + r.value_v[k], 1e-12) << k;
    if (k > 0) {
      // The command logged at k - 1 is what moved the joint to the reading logged at k, and
      // what the load cell of this device shows.
      ASSERT_NEAR(q[k] - q[k - 1], device.gain_radps_per_v * kT * u[k - 1], 1e-12) << k;
      ASSERT_NEAR(tau[k], 100.0 * u[k - 1], 1e-9) << k;
      ASSERT_NEAR(t[k] - t[k - 1], kT, 1e-12);
    }
  }
  // The settling period ran before the first logged row (100 reads, plus the initial one).
  EXPECT_NEAR(t.front(), 0.101, 1e-9);
}

TEST(ExperimentTest, LogsTheHeldJointsAnglesUnderTheirNamesAndReadsBackTheirMeans) {
  IntegratorDevice device(3, 0.0);
  const SampledSignal r = linearChirp(0.5, 1.0, 20.0, 0.5, kT);
  ExperimentOptions options;
  options.joint = 1;
  options.settle_s = 0.05;
  options.joint_names = {"SFE", "EB", "WR"};
  const ExperimentResult result = runExperiment(device, r, options);
  ASSERT_TRUE(result.completed) << result.stop_reason;
  ASSERT_EQ(result.log.names.size(), kExperimentColumns.size() + 2);
  EXPECT_EQ(result.log.names[kExperimentColumns.size()], "held_SFE_rad");
  EXPECT_EQ(result.log.names[kExperimentColumns.size() + 1], "held_WR_rad");
  EXPECT_FALSE(result.log.has("held_EB_rad"));  // the driven joint's angle is q_rad
  // The held joints start at 0.2 rad and their holds keep them there (no excitation, no load):
  // the integrator device moves a held joint only by its own hold command, which is zero at 0.2.
  const std::vector<HeldAngle> held = heldAngles(result.log);
  ASSERT_EQ(held.size(), 2u);
  EXPECT_EQ(held[0].joint, "SFE");
  EXPECT_EQ(held[1].joint, "WR");
  for (const HeldAngle& h : held) EXPECT_NEAR(h.mean_rad, 0.2, 1e-12);

  // heldAngles averages each held_<joint>_rad column, whatever its values, and leaves the other
  // angle columns alone (the driven joint's q_rad, a tool's q_cmd_rad).
  SignalTable table;
  table.names = {"time_s", "q_rad", "held_SAA_rad", "q_cmd_rad", "tau_SAA_nm"};
  table.columns = {{0.0, 0.001, 0.002}, {5.0, 5.0, 5.0}, {0.1, 0.2, 0.6}, {7.0, 7.0, 7.0}, {1.0, 2.0, 3.0}};
  const std::vector<HeldAngle> means = heldAngles(table);
  ASSERT_EQ(means.size(), 1u);
  EXPECT_EQ(means[0].joint, "SAA");
  EXPECT_DOUBLE_EQ(means[0].mean_rad, 0.3);
  EXPECT_EQ(heldAngleColumn("SAA"), "held_SAA_rad");

  // Names that are not one usable name per device joint are refused before the arm moves.
  IntegratorDevice fresh(3, 0.0);
  options.joint_names = {"SFE", "EB"};
  EXPECT_THROW((void)runExperiment(fresh, r, options), std::invalid_argument);
  options.joint_names = {"SFE", "EB", "SFE"};
  EXPECT_THROW((void)runExperiment(fresh, r, options), std::invalid_argument);
  options.joint_names = {"SFE", "E,B", "WR"};
  EXPECT_THROW((void)runExperiment(fresh, r, options), std::invalid_argument);
  options.joint_names = {"SFE", "", "WR"};
  EXPECT_THROW((void)runExperiment(fresh, r, options), std::invalid_argument);
  EXPECT_NE(fresh.state(), hil::IoState::kActive);
  EXPECT_EQ(fresh.appliedCommand()[0], 0.0);
}

TEST(ExperimentTest, StopsSafelyBeforeTheLimitAndOnDeviceFaults) {
  IntegratorDevice device(2, 0.0);
  ExperimentOptions options;
  options.joint = 0;
  options.settle_s = 0.0;
  options.hold_gain_v_per_rad = 0.0;
  options.min_rad = -1.0;
  options.max_rad = 0.5;
  const SampledSignal push = stepSequence({10.0}, 2.0, kT);  // 5 rad/s towards the upper limit
  const ExperimentResult result = runExperiment(device, push, options);
  EXPECT_FALSE(result.completed);
  EXPECT_NE(result.stop_reason.find("limits"), std::string::npos) << result.stop_reason;
  ASSERT_GT(result.log.rows(), 0u);
  for (double q : result.log.column("q_rad")) EXPECT_LE(q, 0.45);
  EXPECT_EQ(device.state(), hil::IoState::kInactive);
  EXPECT_EQ(device.appliedCommand()[0], 0.0);

  IntegratorDevice failing(2, 0.0);
  failing.fail_read_at = 50;
  options.max_rad = 10.0;
  const ExperimentResult failed = runExperiment(failing, stepSequence({0.1}, 1.0, kT), options);
  EXPECT_FALSE(failed.completed);
  EXPECT_NE(failed.stop_reason.find("read failed"), std::string::npos) << failed.stop_reason;
  EXPECT_EQ(failing.appliedCommand()[0], 0.0);
}

TEST(ExperimentTest, RejectsBadSetups) {
  IntegratorDevice device(2, 0.0);
  ExperimentOptions options;
  options.joint = 2;
  EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), std::invalid_argument);
  options.joint = 0;
  EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, 2 * kT), options), std::invalid_argument);
  options.min_rad = 0.0;
  options.max_rad = 0.05;
  EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), std::invalid_argument);
  // A hold angle outside the limits less the margin, or not finite; move settings that are not
  // positive and finite.
  options.max_rad = 1.0;
  for (double hold : {0.02, 0.96, std::nan(""), std::numeric_limits<double>::infinity()}) {
    options.hold_rad = hold;
    EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), std::invalid_argument) << hold;
  }
  options.hold_rad = 0.5;
  options.move_s = 0.0;
  EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), std::invalid_argument);
  options.move_s = 1.0;
  options.move_speed_radps = std::numeric_limits<double>::infinity();
  EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), std::invalid_argument);
  options.move_speed_radps = 0.2;
  options.move_max_error_rad = std::numeric_limits<double>::infinity();
  EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), std::invalid_argument);
  // No excitation to run; a settling time that is negative or not finite.
  options.move_max_error_rad = 0.1;
  EXPECT_THROW((void)runExperiments(device, {}, options), std::invalid_argument);
  for (double settle : {-0.1, std::nan(""), std::numeric_limits<double>::infinity()}) {
    options.settle_s = settle;
    EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), std::invalid_argument) << settle;
  }
  EXPECT_NE(device.state(), hil::IoState::kActive);
  EXPECT_EQ(device.appliedCommand()[0], 0.0);
}

// A device that cannot be read, a first reading out of range, or one beyond the joint's own
// limits is no posture to move from (a device, sensor, calibration or limits that are wrong): a
// device error before anything moves, with or without a hold angle.
TEST(ExperimentTest, AStartReadingOutOfRangeOrBeyondTheLimitsIsADeviceError) {
  ExperimentOptions options;
  options.joint = 0;
  options.min_rad = 0.18;
  options.max_rad = 1.5;
  IntegratorDevice unreadable(2, 0.0);
  unreadable.fail_read_at = 0;
  EXPECT_THROW((void)runExperiment(unreadable, stepSequence({0.0}, 0.1, kT), options), hil::DeviceError);
  EXPECT_NE(unreadable.state(), hil::IoState::kActive);
  for (const double start : {std::nan(""), 0.17, 1.51}) {
    for (const bool with_hold : {false, true}) {
      IntegratorDevice device(2, 0.0);
      device.startAt(start);
      options.hold_rad = with_hold ? std::optional<double>(0.5) : std::nullopt;
      EXPECT_THROW((void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options), hil::DeviceError)
          << start << " " << with_hold;
      EXPECT_NE(device.state(), hil::IoState::kActive);
      EXPECT_EQ(device.appliedCommand()[0], 0.0);
    }
  }
}

// A driven joint that starts within the margin of a limit (an arm resting at its stop) is
// refused before the device is activated, naming the joint, its angle and the range; given a
// hold angle, the joint first moves there.
TEST(ExperimentTest, RefusesAStartInsideTheMarginUnlessAHoldAngleMovesItOut) {
  IntegratorDevice device(2, 0.0);  // every joint starts at 0.2 rad
  ExperimentOptions options;
  options.joint = 1;
  options.joint_names = {"SFE", "EB"};
  options.settle_s = 0.1;
  options.min_rad = 0.18;  // 0.2 rad is within the 0.05 rad margin
  options.max_rad = 1.5;
  try {
    (void)runExperiment(device, stepSequence({0.0}, 0.1, kT), options);
    ADD_FAILURE() << "expected ExperimentRefused";
  } catch (const ExperimentRefused& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("EB starts at 0.200000 rad"), std::string::npos) << what;
    EXPECT_NE(what.find("0.230000..1.450000 rad"), std::string::npos) << what;
    EXPECT_NE(what.find("hold angle"), std::string::npos) << what;
  }
  EXPECT_NE(device.state(), hil::IoState::kActive);
  EXPECT_EQ(device.appliedCommand()[1], 0.0);

  options.hold_rad = 0.5;
  options.settle_s = 1.0;
  const ExperimentResult moved = runExperiment(device, linearChirp(0.05, 1.0, 20.0, 0.5, kT), options);
  ASSERT_TRUE(moved.completed) << moved.stop_reason;
  EXPECT_DOUBLE_EQ(moved.hold_rad[1], 0.5);
  EXPECT_DOUBLE_EQ(moved.hold_rad[0], 0.2);
  for (double q : moved.log.column("q_rad")) EXPECT_NEAR(q, 0.5, 0.01);
  for (double q : moved.log.column("held_SFE_rad")) EXPECT_DOUBLE_EQ(q, 0.2);

  // The same at the upper limit: a joint resting inside the upper margin moves down to its hold.
  IntegratorDevice high(2, 0.0);
  high.startAt(1.49);
  options.min_rad = -1.0;
  options.max_rad = 1.5;
  ExperimentOptions without_hold = options;
  without_hold.hold_rad.reset();
  EXPECT_THROW((void)runExperiment(high, stepSequence({0.0}, 0.1, kT), without_hold), ExperimentRefused);
  const ExperimentResult down = runExperiment(high, linearChirp(0.05, 1.0, 20.0, 0.5, kT), options);
  ASSERT_TRUE(down.completed) << down.stop_reason;
  for (double q : down.log.column("q_rad")) EXPECT_NEAR(q, 0.5, 0.01);
}

// Once the move has ended the joint is held to the limits less the margin again: a hold angle
// just inside the margin, then a push towards the limit, stops the run at the margin, not at the
// relaxed band the move from inside the margin had.
TEST(ExperimentTest, TheMarginHoldsAgainOnceTheMoveHasEnded) {
  IntegratorDevice device(2, 0.0);
  ExperimentOptions options;
  options.joint = 0;
  options.settle_s = 0.5;
  options.min_rad = 0.18;  // starts at 0.2, inside the margin (0.23)
  options.max_rad = 1.5;
  options.hold_rad = 0.235;
  const ExperimentResult result = runExperiment(device, stepSequence({-2.0}, 0.5, kT), options);
  EXPECT_FALSE(result.completed);
  EXPECT_NE(result.stop_reason.find("of its limits"), std::string::npos) << result.stop_reason;
  EXPECT_EQ(result.stop_reason.find("moving"), std::string::npos) << result.stop_reason;
  ASSERT_GT(result.log.rows(), 0u);
  for (double q : result.log.column("q_rad")) EXPECT_GE(q, 0.23);
  EXPECT_EQ(device.appliedCommand()[0], 0.0);
}

// The move: the hold target follows a cosine blend from the start to the hold angle over
// max(move_s, distance / move_speed_radps), then the settling time and the excitation about the
// hold angle. Each command written is K (target - q) with the target recomputed here from the
// blend's closed form.
TEST(ExperimentTest, MovesToTheHoldAngleAlongACosineBlendThenExcitesAboutIt) {
  IntegratorDevice device(3, 0.0);
  device.recorded_joint = 1;
  device.read_q.reserve(10000);
  device.written_u.reserve(10000);
  ExperimentOptions options;
  options.joint = 1;
  options.settle_s = 1.0;
  options.hold_rad = 0.6;  // from 0.2 rad: 0.4 rad at 0.2 rad/s on average, 2 s (longer than move_s)
  const SampledSignal r = linearChirp(0.05, 1.0, 20.0, 0.5, kT);
  const ExperimentResult result = runExperiment(device, r, options);
  ASSERT_TRUE(result.completed) << result.stop_reason;
  constexpr std::size_t kMoveSteps = 2000;
  constexpr std::size_t kSettleSteps = 1000;
  // The device writes its safe output (zero) when configured and when deactivated, around the
  // run's commands; its ramp-in puts out the safe output at the first command after activation.
  ASSERT_EQ(device.written_u.size(), 1 + kMoveSteps + kSettleSteps + r.value_v.size() + 1);
  EXPECT_EQ(device.written_u.front(), 0.0);
  EXPECT_EQ(device.written_u[1], 0.0);
  EXPECT_EQ(device.written_u.back(), 0.0);
  const double K = options.hold_gain_v_per_rad;
  for (std::size_t k = 1; k < kMoveSteps; ++k) {
    const double s = static_cast<double>(k + 1) / static_cast<double>(kMoveSteps);
    const double target = 0.2 + 0.4 * (0.5 - 0.5 * std::cos(std::acos(-1.0) * s));
    ASSERT_NEAR(device.written_u[1 + k], K * (target - device.read_q[k]), 1e-12) << k;
  }
  for (std::size_t k = kMoveSteps; k < kMoveSteps + kSettleSteps; ++k) {
    ASSERT_NEAR(device.written_u[1 + k], K * (0.6 - device.read_q[k]), 1e-12) << k;
  }
  // The log starts with the excitation, the hold law about the hold angle.
  const auto& u = result.log.column("command_v");
  const auto& q = result.log.column("q_rad");
  for (std::size_t k = 0; k < r.value_v.size(); ++k) {
    ASSERT_NEAR(u[k], K * (0.6 - q[k]) + r.value_v[k], 1e-12) << k;
  }
  EXPECT_NEAR(q.front(), 0.6, 1e-3);
  EXPECT_NEAR(result.log.column("time_s").front(), 0.001 * (1 + kMoveSteps + kSettleSteps), 1e-9);
  EXPECT_DOUBLE_EQ(result.hold_rad[1], 0.6);

  // With the control time logged, the log's clock starts at the first excitation reading, after
  // the move and the settling, one period a row.
  IntegratorDevice again(3, 0.0);
  options.log_control_time = true;
  const ExperimentResult timed = runExperiment(again, r, options);
  ASSERT_TRUE(timed.completed) << timed.stop_reason;
  const auto& t = timed.log.column("time_s");
  EXPECT_NEAR(t.front(), 0.001 * (1 + kMoveSteps + kSettleSteps), 1e-9);
  for (std::size_t k = 1; k < t.size(); ++k) ASSERT_NEAR(t[k] - t[0], static_cast<double>(k) * kT, 1e-12) << k;
}

// Several experiments in one activation: the joint carries a load (0.35 V, a droop of 0.035 rad
// under the 10 V/rad hold) and the first excitation pushes it 0.05 rad further off its hold; the
// second experiment still holds it at the first's hold angle, its first reading (0.2 rad less
// the first period's sag), with no new ramp-in, every command K (hold - q) + r once the single
// ramp-in is over. Each log keeps its own
// control time. A stop during the first leaves the second not run and the valve at null.
TEST(ExperimentTest, SeveralExperimentsRunInOneActivationTheHoldsContinuing) {
  ExperimentOptions options;
  options.joint = 0;
  options.settle_s = 0.6;  // longer than the ramp-in
  options.min_rad = 0.0;
  options.max_rad = 1.5;
  options.log_control_time = true;
  const std::vector<SampledSignal> excitations{stepSequence({-0.5}, 0.3, kT), stepSequence({0.2}, 0.3, kT)};
  constexpr std::size_t kSettle = 600, kLength = 300;

  IntegratorDevice device(1, 0.5);
  device.gain_radps_per_v = 5.0;
  device.load_v = 0.35;
  device.read_q.reserve(4000);
  device.written_u.reserve(4000);
  const std::vector<ExperimentResult> results = runExperiments(device, excitations, options);
  ASSERT_EQ(results.size(), 2u);
  const double hold = device.read_q.front();
  EXPECT_NEAR(hold, 0.2, 0.002);
  for (const ExperimentResult& r : results) {
    ASSERT_TRUE(r.completed) << r.stop_reason;
    EXPECT_EQ(r.log.rows(), kLength);
    EXPECT_DOUBLE_EQ(r.hold_rad[0], hold);
    const auto& t = r.log.column("time_s");
    for (std::size_t k = 1; k < t.size(); ++k) ASSERT_NEAR(t[k] - t[0], static_cast<double>(k) * kT, 1e-12) << k;
  }
  // One activation: the safe output when configured, the commands, the safe output at the end.
  constexpr std::size_t kSteps = 2 * (kSettle + kLength);
  ASSERT_EQ(device.written_u.size(), 1 + kSteps + 1);
  EXPECT_EQ(device.written_u.front(), 0.0);
  EXPECT_EQ(device.written_u.back(), 0.0);
  const double K = options.hold_gain_v_per_rad;
  for (std::size_t k = kSettle; k < kSteps; ++k) {
    const double r = k < kSettle + kLength ? -0.5 : k >= 2 * kSettle + kLength ? 0.2 : 0.0;
    ASSERT_NEAR(device.written_u[1 + k], K * (hold - device.read_q[k]) + r, 1e-12) << k;
  }
  // The first excitation took the joint 0.05 rad below its droop; after its settling time the
  // second finds it back at the droop below the same hold and lifts it 0.02 rad above it. Each
  // log has its own excitation.
  EXPECT_NEAR(results[0].log.column("q_rad").back(), hold - 0.035 - 0.05, 1e-3);
  EXPECT_NEAR(results[1].log.column("q_rad").front(), hold - 0.035, 1e-3);
  EXPECT_NEAR(results[1].log.column("q_rad").back(), hold - 0.035 + 0.02, 1e-3);
  for (double r : results[0].log.column("excitation_v")) ASSERT_EQ(r, -0.5);
  for (double r : results[1].log.column("excitation_v")) ASSERT_EQ(r, 0.2);

  // Excitations with no samples, and no settling time: each counts as run whole.
  IntegratorDevice quick(1, 0.0);
  ExperimentOptions at_once = options;
  at_once.settle_s = 0.0;
  const SampledSignal none{kT, {}, {}};
  const std::vector<ExperimentResult> empty = runExperiments(quick, {excitations[0], none, none}, at_once);
  ASSERT_EQ(empty.size(), 3u);
  for (const ExperimentResult& r : empty) EXPECT_TRUE(r.completed) << r.stop_reason;
  EXPECT_EQ(empty[0].log.rows(), kLength);
  EXPECT_EQ(empty[2].log.rows(), 0u);

  IntegratorDevice failing(1, 0.5);
  failing.fail_read_at = static_cast<int>(kSettle + 100);
  const std::vector<ExperimentResult> stopped = runExperiments(failing, excitations, options);
  ASSERT_EQ(stopped.size(), 2u);
  EXPECT_FALSE(stopped[0].completed);
  EXPECT_GT(stopped[0].log.rows(), 0u);
  EXPECT_NE(stopped[0].stop_reason.find("scripted read failure"), std::string::npos) << stopped[0].stop_reason;
  EXPECT_FALSE(stopped[1].completed);
  EXPECT_EQ(stopped[1].log.rows(), 0u);
  EXPECT_EQ(stopped[1].stop_reason.rfind("not run: ", 0), 0u) << stopped[1].stop_reason;
  EXPECT_NE(failing.state(), hil::IoState::kActive);
  EXPECT_EQ(failing.appliedCommand()[0], 0.0);
}

// Fault injection during the move: a read failure, a joint that does not follow its target (a
// stuck valve), and one that moves the wrong way from inside the margin (a reversed valve or
// sensor) each stop the run with the valves at null before the excitation starts.
TEST(ExperimentTest, StopsSafelyDuringTheMove) {
  ExperimentOptions options;
  options.joint = 0;
  options.settle_s = 0.1;
  options.min_rad = -1.0;
  options.max_rad = 1.0;
  options.hold_rad = 0.6;
  const SampledSignal r = stepSequence({0.1}, 0.5, kT);

  IntegratorDevice failing(2, 0.0);
  failing.fail_read_at = 500;
  const ExperimentResult failed = runExperiment(failing, r, options);
  EXPECT_FALSE(failed.completed);
  EXPECT_NE(failed.stop_reason.find("read failed"), std::string::npos) << failed.stop_reason;
  EXPECT_EQ(failed.log.rows(), 0u);
  EXPECT_NE(failing.state(), hil::IoState::kActive);
  EXPECT_EQ(failing.appliedCommand()[0], 0.0);

  IntegratorDevice stuck(2, 0.0);
  stuck.gain_radps_per_v = 0.0;
  const ExperimentResult stopped = runExperiment(stuck, r, options);
  EXPECT_FALSE(stopped.completed);
  EXPECT_NE(stopped.stop_reason.find("from its target moving to its hold angle"), std::string::npos)
      << stopped.stop_reason;
  EXPECT_EQ(stopped.log.rows(), 0u);
  EXPECT_EQ(stuck.appliedCommand()[0], 0.0);

  IntegratorDevice reversed(2, 0.0);
  reversed.gain_radps_per_v = -0.5;
  reversed.recorded_joint = 0;
  reversed.read_q.reserve(10000);
  options.min_rad = 0.18;  // starts inside the margin; moving the wrong way approaches the stop
  const ExperimentResult towards = runExperiment(reversed, r, options);
  EXPECT_FALSE(towards.completed);
  EXPECT_NE(towards.stop_reason.find("of its limits"), std::string::npos) << towards.stop_reason;
  EXPECT_NE(towards.stop_reason.find("moving to its hold angle"), std::string::npos) << towards.stop_reason;
  EXPECT_EQ(towards.log.rows(), 0u);
  EXPECT_EQ(reversed.appliedCommand()[0], 0.0);
  // It was let go below its start, to the relaxed band (the start less half the margin,
  // 0.175 rad), and stopped on the first reading past it.
  ASSERT_GE(reversed.read_q.size(), 3u);
  for (std::size_t k = 0; k + 1 < reversed.read_q.size(); ++k) EXPECT_GE(reversed.read_q[k], 0.175) << k;
  EXPECT_LT(reversed.read_q.back(), 0.175);
  EXPECT_LT(reversed.read_q[reversed.read_q.size() - 2], 0.18);
}

}  // namespace
}  // namespace fullarm::identification
