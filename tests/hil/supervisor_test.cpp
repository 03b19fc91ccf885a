// The safety supervisor: each check trips with its cause, joint and value; the trip latches
// until an explicit reset; the start-up guard; the contact fade of stale minima (the fade time
// and the rate bound); the output limits. Allocation-free.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "alloc_guard.hpp"
#include "fullarm/hil/supervisor.hpp"
#include "hil_fixture.hpp"

namespace fullarm::hil {
namespace {

constexpr double kPeriod_s = 1e-3;

class SupervisorTest : public ::testing::Test {
 protected:
  SupervisorTest() : joints_(arm::JointSelection::all(7)) {
    params_.startup_valid_s = 0.01;
    model_ = makeSupervisorModel(params_, test::model(), joints_, IoVector::Constant(7, 10.0), kPeriod_s);
    resetSupervisor(model_, data_, test::model().numJoints());
    q_ = test::restPosture().head(7);
  }

  // Runs `ticks` ticks at q_ (plus `dq` per tick); returns whether forces were allowed at the end.
  bool run(int ticks, const SupervisorRequests& requests = {}, double dq = 0.0) {
    bool running = false;
    for (int i = 0; i < ticks; ++i) {
      q_[3] += dq;
      running = step(test::sampleAt(q_), requests);
      if (data_.state == SupervisorState::kTripped) break;  // keep the trip's events for the checks
    }
    return running;
  }
  bool step(const JointSample& sample, const SupervisorRequests& requests = {}, core::RtStatus device = {}) {
    ++tick_;
    return supervisorCheckInputs(model_, data_, tick_, static_cast<double>(tick_) * kPeriod_s, sample, device, requests);
  }
  void expectTrip(SupervisorCause cause, int joint) {
    EXPECT_EQ(data_.state, SupervisorState::kTripped);
    EXPECT_EQ(data_.trip_cause, cause) << supervisorCauseName(data_.trip_cause);
    bool logged = false;
    for (int i = 0; i < data_.num_events; ++i) {
      const SupervisorEvent& e = data_.events[static_cast<std::size_t>(i)];
      if (e.trip && e.cause == cause) {
        logged = true;
        EXPECT_EQ(e.joint, joint);
        EXPECT_EQ(e.tick, tick_);
        EXPECT_DOUBLE_EQ(e.t_s, static_cast<double>(tick_) * kPeriod_s);
      }
    }
    EXPECT_TRUE(logged) << "no trip event with cause " << supervisorCauseName(cause);
    IoVector valves = IoVector::Constant(7, 1.0);
    supervisorLimitOutputs(model_, data_, valves);
    EXPECT_EQ(valves, IoVector::Zero(7)) << "a tripped supervisor puts every valve at null";
  }

  SupervisorParams params_;
  arm::JointSelection joints_;
  SupervisorModel model_;
  SupervisorData data_;
  IoVector q_;
  std::uint64_t tick_ = 0;
};

TEST_F(SupervisorTest, StartupGuardHoldsTheForcesUntilTheSensorsHaveBeenValidLongEnough) {
  EXPECT_FALSE(run(5));
  EXPECT_EQ(data_.state, SupervisorState::kStartup);
  IoVector valves = IoVector::Constant(7, 1.0);
  supervisorLimitOutputs(model_, data_, valves);
  EXPECT_EQ(valves, IoVector::Zero(7));
  EXPECT_TRUE(run(10));
  EXPECT_EQ(data_.state, SupervisorState::kRunning);
  valves = IoVector::Constant(7, 1.0);
  supervisorLimitOutputs(model_, data_, valves);
  EXPECT_EQ(valves, IoVector::Constant(7, 1.0));
}

TEST_F(SupervisorTest, StartupGuardWaitsForTheArmInsideItsLimits) {
  q_[0] = test::model().joints[0].limits.max_rad + 0.01;  // outside the range, inside the trip margin
  EXPECT_FALSE(run(50));
  EXPECT_EQ(data_.state, SupervisorState::kStartup);
  q_[0] -= 0.015;  // a plausible step back inside
  EXPECT_FALSE(run(5));
  EXPECT_TRUE(run(20));
}

TEST_F(SupervisorTest, NanReadingTrips) {
  ASSERT_TRUE(run(20));
  JointSample s = test::sampleAt(q_);
  s.tau_load_cell_nm[4] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(step(s));
  expectTrip(SupervisorCause::kSensorNonFinite, 4);
}

TEST_F(SupervisorTest, OutOfRangeReadingTrips) {
  ASSERT_TRUE(run(20));
  JointSample s = test::sampleAt(q_);
  s.q_rad[2] = std::numeric_limits<double>::quiet_NaN();
  s.out_of_range_mask = 1u << 2;
  EXPECT_FALSE(step(s));
  expectTrip(SupervisorCause::kSensorOutOfRange, 2);
}

TEST_F(SupervisorTest, ImplausibleJumpTrips) {
  ASSERT_TRUE(run(20));
  JointSample s = test::sampleAt(q_);
  s.q_rad[1] += 0.05;  // 50 rad/s over one period
  EXPECT_FALSE(step(s));
  expectTrip(SupervisorCause::kSensorRate, 1);
}

TEST_F(SupervisorTest, VelocityLimitTrips) {
  ASSERT_TRUE(run(20));
  // 6 rad/s on the elbow (limit 3 rad/s x 1.5), plausible per step: trips once the filter sees it.
  EXPECT_FALSE(run(100, {}, 6.0 * kPeriod_s));
  expectTrip(SupervisorCause::kVelocityLimit, 3);
  EXPECT_GT(std::abs(data_.events[0].value), 4.5);
}

TEST_F(SupervisorTest, SlowMotionDoesNotTrip) {
  ASSERT_TRUE(run(20));
  EXPECT_TRUE(run(300, {}, 2.0 * kPeriod_s));
}

TEST_F(SupervisorTest, PositionLimitTrips) {
  q_[0] = test::model().joints[0].limits.max_rad - 0.005;
  ASSERT_TRUE(run(20));
  q_[0] += 0.01;  // beyond the range but inside the margin: no trip
  ASSERT_TRUE(run(1));
  q_[0] += 0.012;  // max + 0.017: still inside the margin
  ASSERT_TRUE(run(1));
  q_[0] += 0.012;  // max + 0.029: beyond the margin, in a plausible step
  EXPECT_FALSE(step(test::sampleAt(q_)));
  expectTrip(SupervisorCause::kPositionLimit, 0);
}

TEST_F(SupervisorTest, TorqueLimitTrips) {
  ASSERT_TRUE(run(20));
  JointSample s = test::sampleAt(q_);
  s.tau_load_cell_nm[5] = -1.3 * test::model().joints[5].limits.torque_nm;
  EXPECT_FALSE(step(s));
  expectTrip(SupervisorCause::kTorqueLimit, 5);
}

TEST_F(SupervisorTest, ValveCommandBeyondItsLimitTrips) {
  ASSERT_TRUE(run(20));
  IoVector valves = IoVector::Constant(7, 2.0);
  valves[6] = 10.5;
  supervisorLimitOutputs(model_, data_, valves);
  EXPECT_EQ(valves, IoVector::Zero(7));
  expectTrip(SupervisorCause::kValveCommandLimit, 6);
}

TEST_F(SupervisorTest, EstopLatchesUntilAnExplicitResetAndThenStartsUpAgain) {
  ASSERT_TRUE(run(20));
  SupervisorRequests estop;
  estop.estop_command = true;
  EXPECT_FALSE(run(1, estop));
  expectTrip(SupervisorCause::kEstopCommand, -1);
  // The cause is gone, the latch stays.
  EXPECT_FALSE(run(100));
  EXPECT_EQ(data_.trip_cause, SupervisorCause::kEstopCommand);
  // A later trip does not replace the first cause.
  SupervisorRequests signal;
  signal.estop_signal = true;
  EXPECT_FALSE(run(1, signal));
  EXPECT_EQ(data_.trip_cause, SupervisorCause::kEstopCommand);
  SupervisorRequests reset;
  reset.reset_command = true;
  EXPECT_FALSE(run(1, reset));
  EXPECT_EQ(data_.state, SupervisorState::kStartup);
  EXPECT_EQ(data_.events[0].cause, SupervisorCause::kReset);
  EXPECT_TRUE(run(20));
}

TEST_F(SupervisorTest, SignalTrips) {
  ASSERT_TRUE(run(20));
  SupervisorRequests r;
  r.estop_signal = true;
  EXPECT_FALSE(run(1, r));
  expectTrip(SupervisorCause::kEstopSignal, -1);
}

TEST_F(SupervisorTest, LostHeartbeatTrips) {
  SupervisorRequests r;
  r.heartbeat_enabled = true;
  for (int i = 0; i < 100; ++i) {
    r.heartbeat = static_cast<std::uint64_t>(i / 10);  // changes every 10 ms: alive
    const bool running = run(1, r);
    if (i < 8 || i > 12) {
      ASSERT_EQ(running, i >= 10) << i;
    }
  }
  // It stops: trips once heartbeat_timeout_s has passed, not before.
  const int timeout_ticks = static_cast<int>(params_.heartbeat_timeout_s / kPeriod_s);
  EXPECT_TRUE(run(timeout_ticks - 15, r));  // the last change was 9 ticks before the loop ended
  EXPECT_FALSE(run(10, r));
  EXPECT_EQ(data_.trip_cause, SupervisorCause::kHeartbeatLost);
}

TEST_F(SupervisorTest, ALostPeerHeartbeatIsCommunicationLoss) {
  ASSERT_TRUE(run(20));
  SupervisorRequests r;
  EXPECT_TRUE(run(5, r));  // heard: nothing happens
  r.peer_heartbeat_lost = true;
  EXPECT_FALSE(run(1, r));
  expectTrip(SupervisorCause::kPeerHeartbeatLost, -1);
  EXPECT_STRNE(supervisorCauseName(SupervisorCause::kPeerHeartbeatLost), "unknown");
  // Latched: the peer heard again does not release it; a reset does.
  r.peer_heartbeat_lost = false;
  EXPECT_FALSE(run(5, r));
  EXPECT_EQ(data_.trip_cause, SupervisorCause::kPeerHeartbeatLost);
}

TEST_F(SupervisorTest, OverrunAndDeviceFaultsTrip) {
  ASSERT_TRUE(run(20));
  SupervisorRequests r;
  r.overrun_fault = true;
  EXPECT_FALSE(run(1, r));
  expectTrip(SupervisorCause::kOverrun, -1);

  resetSupervisor(model_, data_, test::model().numJoints());
  ASSERT_TRUE(run(20));
  EXPECT_FALSE(step(test::sampleAt(q_), {}, core::RtStatus::fault(core::RtCode::kBadInput, kFaultDeviceRead, "x")));
  expectTrip(SupervisorCause::kDeviceFault, -1);

  // A remote device's lost link is its own cause.
  resetSupervisor(model_, data_, test::model().numJoints());
  ASSERT_TRUE(run(20));
  EXPECT_FALSE(step(test::sampleAt(q_), {},
                    core::RtStatus::fault(core::RtCode::kBadState, kFaultDeviceRead | kFaultLinkLost, "x")));
  expectTrip(SupervisorCause::kCommunicationLost, -1);
}

TEST_F(SupervisorTest, StaleMinimaFadeTheContactTorquesWithinTheRateBound) {
  ASSERT_TRUE(run(20));
  const int n = test::model().numJoints();
  Eigen::VectorXd tau_in = Eigen::VectorXd::Zero(n);
  tau_in[3] = -12.0;
  tau_in[0] = 30.0;
  const double stale_after_s = params_.stale_global_periods * params_.global_period_s;
  const double max_step = params_.max_fade_rate_nm_per_s * kPeriod_s;
  Eigen::VectorXd previous = tau_in;
  int faded_at = -1;
  for (int i = 0; i < 1000; ++i) {
    const double age_s = i * kPeriod_s;
    Eigen::VectorXd tau = tau_in;
    supervisorFadeContact(model_, data_, age_s, tau);
    if (age_s <= stale_after_s) {
      EXPECT_EQ(tau, tau_in) << "fresh minima are not faded";
    }
    EXPECT_LE((tau - previous).cwiseAbs().maxCoeff(), max_step + 1e-12) << "tick " << i;
    if (faded_at < 0 && tau.isZero(0.0)) faded_at = i;
    previous = tau;
  }
  // Faded over fade_s, but the 30 N m joint needs 0.3 s at 100 N m/s: the rate bound wins.
  ASSERT_GE(faded_at, 0);
  const double fade_time_s = (faded_at * kPeriod_s) - stale_after_s;
  EXPECT_GE(fade_time_s, 30.0 / params_.max_fade_rate_nm_per_s - 2 * kPeriod_s);
  EXPECT_LE(fade_time_s, 30.0 / params_.max_fade_rate_nm_per_s + 2 * kPeriod_s);
  // A fresh set brings the forces back, again no faster than the bound.
  for (int i = 0; i < 400; ++i) {
    Eigen::VectorXd tau = tau_in;
    supervisorFadeContact(model_, data_, 0.0, tau);
    EXPECT_LE((tau - previous).cwiseAbs().maxCoeff(), max_step + 1e-12);
    previous = tau;
  }
  EXPECT_EQ(previous, tau_in);
}

TEST_F(SupervisorTest, StepsDoNotAllocate) {
  const JointSample s = test::sampleAt(q_);
  Eigen::VectorXd tau = Eigen::VectorXd::Ones(test::model().numJoints());
  IoVector valves = IoVector::Constant(7, 1.0);
  for (int i = 0; i < 50; ++i) {
    ++tick_;
    EXPECT_NO_HEAP_ALLOCATION(supervisorCheckInputs(model_, data_, tick_, static_cast<double>(tick_) * kPeriod_s, s, {}, {}));
    EXPECT_NO_HEAP_ALLOCATION(supervisorFadeContact(model_, data_, i * 1e-3, tau));
    EXPECT_NO_HEAP_ALLOCATION(supervisorLimitOutputs(model_, data_, valves));
  }
}

}  // namespace
}  // namespace fullarm::hil
