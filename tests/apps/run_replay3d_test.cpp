// The run report's 3D replay built from a run's telemetry: the frame rate and its cap, a touch
// shorter than a frame still marked, capsules that keep their length (rigid links posed by
// forward kinematics), the adopted minima per frame, and the summary's first penetration.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "fullarm/hil/run.hpp"
#include "run_replay3d.hpp"

namespace fullarm::app {
namespace {

// The default run's model, scene and tick, without a device.
const hil::HilSession& session() {
  static const hil::HilSession s(hil::RunOptions{}, false);
  return s;
}

// `ticks` ticks of telemetry, the device joints swinging slowly.
hil::RunResult syntheticRun(std::size_t ticks) {
  const hil::HilSession& s = session();
  const double period_s = s.config().control_period_s;
  hil::RunResult r;
  for (const arm::Joint& j : s.model().joints) r.link_names.push_back(j.name);
  for (int k = 0; k < s.tickModel().device_joints.size(); ++k) {
    std::string name = "J";  // appended, not operator+: GCC 12 reports a false -Wrestrict on that at -O2
    name += std::to_string(k);
    r.joint_names.push_back(std::move(name));
  }
  r.telemetry.resize(ticks);
  for (std::size_t k = 0; k < ticks; ++k) {
    hil::TickTelemetry& t = r.telemetry[k];
    t.tick = k;
    t.t_s = static_cast<double>(k) * period_s;
    t.num_device_joints = s.tickModel().device_joints.size();
    for (int j = 0; j < t.num_device_joints; ++j)
      t.q_rad[static_cast<std::size_t>(j)] = 0.3 * std::sin(0.5 * t.t_s + j);
  }
  return r;
}

TEST(RunReplay3d, ShowsTwentyFiveFramesPerSecondAndCapsLongRuns) {
  const reports::Replay3d ten = runReplay3d(syntheticRun(10000), session());
  ASSERT_EQ(ten.frames.size(), 250U);
  EXPECT_NEAR(ten.frames[1].t_s - ten.frames[0].t_s, 0.04, 1e-12);
  EXPECT_NEAR(ten.frames.back().t_s, 9.999, 1e-12) << "the last tick is the last frame";
  const reports::Replay3d long_run = runReplay3d(syntheticRun(300000), session());
  EXPECT_LE(long_run.frames.size(), kMaxReplayFrames);
  EXPECT_GE(long_run.frames.size(), kMaxReplayFrames - 1);
}

TEST(RunReplay3d, CapsulesKeepTheirLengthAndATouchShorterThanAFrameShows) {
  hil::RunResult r = syntheticRun(2000);
  const reports::Replay3d plain = runReplay3d(r, session());
  ASSERT_FALSE(plain.links.empty());
  // The capsule links only, each rigid: the same segment length in every frame.
  for (std::size_t l = 0; l < plain.links.size(); ++l) {
    const auto length = [&](std::size_t f) {
      const auto& s = plain.frames[f].segments_m[l];
      return std::hypot(s[3] - s[0], s[4] - s[1], s[5] - s[2]);
    };
    for (std::size_t f = 1; f < plain.frames.size(); ++f)
      EXPECT_NEAR(length(f), length(0), 1e-9) << plain.links[l].name;
  }
  // The last capsule link touches at one tick in the middle of frame 10 (ticks 400 .. 439).
  const std::string touching = plain.links.back().name;
  std::size_t link = 0;
  while (r.link_names[link] != touching) ++link;
  r.telemetry[417].link_penetration_mask = 1U << link;
  const reports::Replay3d replay = runReplay3d(r, session());
  for (std::size_t f = 0; f < replay.frames.size(); ++f) {
    EXPECT_EQ(replay.frames[f].penetrating.back(), f == 10) << "frame " << f;
    for (std::size_t l = 0; l + 1 < replay.links.size(); ++l) EXPECT_FALSE(replay.frames[f].penetrating[l]);
  }
  const nlohmann::json summary = replaySummary(replay, r);
  EXPECT_DOUBLE_EQ(summary["first_penetration_s"][touching].get<double>(), r.telemetry[417].t_s);
  EXPECT_TRUE(summary["first_penetration_s"][plain.links.front().name].is_null());
  EXPECT_EQ(summary["frames"], 50);
}

TEST(RunReplay3d, EachFrameShowsTheNewestAdoptedSet) {
  hil::RunResult r = syntheticRun(400);
  haptics::LocalMinimum m;
  m.link = session().model().numJoints() - 1;
  m.object = 0;
  m.p_O = Eigen::Vector3d(0.1, 0.2, 0.3);
  hil::RecordedSet early{1, 0, 100, {}, {m}, 1};
  hil::RecordedSet late{2, 150, 250, {}, {m, m}, 2};
  hil::RecordedSet never{3, 300, -1, {}, {m, m, m}, 3};
  r.sets = {late, never, early};  // any order
  const reports::Replay3d replay = runReplay3d(r, session());
  ASSERT_EQ(replay.frames.size(), 10U);  // ticks 39, 79, ..., 399
  for (std::size_t f = 0; f < replay.frames.size(); ++f) {
    const std::size_t tick = f * 40 + 39;
    const std::size_t expected = tick >= 250 ? 2 : tick >= 100 ? 1 : 0;
    EXPECT_EQ(replay.frames[f].minima.size(), expected) << "frame " << f;
  }
}

}  // namespace
}  // namespace fullarm::app
