// Contact springs and tailored force Jacobians:
// - Eq. (1)-(2) torques equal J_c(q)^T f from fullarm::arm's point Jacobian (1e-12 relative)
//   for contacts on every link;
// - the spring law against its closed form, damping, saturation, hand-only mode and the per-link
//   contact records, fault injection (non-finite minimum -> zero contact torque + fault);
// - config/haptics.yaml: the shipped file loads; bad values and mutated/truncated text give
//   core::ConfigError naming the key, never a crash;
// - allocation freedom of forces and torques.
#include "fullarm/haptics/contact_forces.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <tuple>

#include "alloc_guard.hpp"
#include "arm_test_util.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::haptics {
namespace {

using Eigen::Vector3d;

TEST(TailoredJacobianTest, EqualsPointJacobianTransposeOnEveryLink) {
  const arm::ArmModel& model = arm::test::defaultModel();
  arm::ArmData fk(model);
  std::mt19937 rng(17);
  std::normal_distribution<double> n(0.0, 1.0);
  arm::PointJacobian J;
  double worst = 0.0;
  for (int trial = 0; trial < 200; ++trial) {
    arm::computeForwardKinematics(model, fk, arm::test::randomConfiguration(model, rng));
    for (int link = 0; link < model.numJoints(); ++link) {
      const Vector3d p_W = fk.X_WL[static_cast<std::size_t>(link)] * Vector3d(0.1 * n(rng), 0.1 * n(rng), 0.1 * n(rng));
      const Vector3d f_W(10 * n(rng), 10 * n(rng), 10 * n(rng));
      Eigen::VectorXd tau = Eigen::VectorXd::Zero(model.numJoints());
      addTailoredJacobianTorques(model, fk, link, p_W, f_W, tau);
      arm::computePointJacobian(model, fk, link, p_W, J);
      const Eigen::VectorXd ref = J.topRows<3>().transpose() * f_W;
      const double rel = (tau - ref).norm() / ref.norm();
      worst = std::max(worst, rel);
      EXPECT_LE(rel, 1e-12) << "link " << link;
      // Joints that do not move the link get nothing.
      for (int j = 0; j < model.numJoints(); ++j) {
        if (!arm::jointMovesLink(model, j, link)) {
          EXPECT_EQ(tau[j], 0.0);
        }
      }
    }
  }
  RecordProperty("worst_relative_error", std::to_string(worst));
}

class ContactForcesTest : public ::testing::Test {
 protected:
  const arm::ArmModel& model_ = arm::test::defaultModel();
  arm::ArmData fk_{model_};
  HapticsParams params_;
  ContactData data_{model_, 64};

  void SetUp() override { arm::computeForwardKinematics(model_, fk_, model_.defaultPosture()); }

  LocalMinimum minimum(int link, double d, const Vector3d& u_W) const {
    LocalMinimum m;
    m.link = link;
    m.object = 0;
    m.p_L = Vector3d(0.01, 0.02, -0.05);
    m.distance_m = d;
    m.u_W = u_W.normalized();
    return m;
  }
};

TEST_F(ContactForcesTest, SpringLawPushesAwayBelowThresholdOnly) {
  const Vector3d u(0.0, 0.6, -0.8);
  std::vector<LocalMinimum> minima{minimum(4, 0.004, u), minimum(4, 0.012, u), minimum(2, 0.0, u)};
  computeContactForces(params_, model_, fk_, minima, 1e-3, data_);
  EXPECT_TRUE(data_.status.ok());
  EXPECT_EQ(data_.active_springs, 2);
  // f = k (d_f - d) along -u.
  EXPECT_NEAR((data_.f_W[0] - (-params_.stiffness_npm * (0.01 - 0.004) * u)).norm(), 0.0, 1e-12);
  EXPECT_EQ(data_.f_W[1].norm(), 0.0);  // beyond d_f
  EXPECT_NEAR(data_.f_W[2].norm(), params_.stiffness_npm * 0.01, 1e-12);
  EXPECT_TRUE(data_.links[4].in_contact);
  EXPECT_NEAR(data_.links[4].depth_m, 0.006, 1e-15);
  EXPECT_TRUE(data_.links[2].penetrating);
  EXPECT_FALSE(data_.links[6].in_contact);
  // Torques: sum over minima of the tailored Jacobian (contact only: no gravity, no kinematics).
  const std::uint64_t fk_passes = fk_.forward_kinematics_passes;
  computeContactTorques(model_, fk_, minima, data_);
  EXPECT_EQ(fk_.forward_kinematics_passes, fk_passes);
  EXPECT_EQ(fk_.gravity_passes, 0u);
  Eigen::VectorXd expected = Eigen::VectorXd::Zero(model_.numJoints());
  arm::PointJacobian J;
  for (int i : {0, 2}) {
    const auto& m = minima[static_cast<std::size_t>(i)];
    const Vector3d p = fk_.X_WL[static_cast<std::size_t>(m.link)] * m.p_L;
    arm::computePointJacobian(model_, fk_, m.link, p, J);
    expected += J.topRows<3>().transpose() * data_.f_W[static_cast<std::size_t>(i)];
  }
  EXPECT_LE((data_.tau_contact_nm - expected).norm(), 1e-12 * expected.norm());
}

TEST_F(ContactForcesTest, DampingSaturationAndPatchNormalisation) {
  const Vector3d u(1, 0, 0);
  LocalMinimum m = minimum(4, 0.005, u);
  m.previous_distance_m = 0.006;  // approaching at 1 m/s over 1 ms
  params_.damping_nspm = 3.0;
  computeContactForces(params_, model_, fk_, std::span<const LocalMinimum>(&m, 1), 1e-3, data_);
  EXPECT_NEAR(data_.f_W[0].x(), -(params_.stiffness_npm * 0.005 + 3.0 * 1.0), 1e-9);
  // Receding fast: damping would pull; the spring never pulls.
  m.previous_distance_m = 0.0;
  computeContactForces(params_, model_, fk_, std::span<const LocalMinimum>(&m, 1), 1e-3, data_);
  EXPECT_EQ(data_.f_W[0].norm(), 0.0);
  // Saturation.
  params_.damping_nspm = 0.0;
  params_.max_force_per_minimum_n = 4.0;
  computeContactForces(params_, model_, fk_, std::span<const LocalMinimum>(&m, 1), 1e-3, data_);
  EXPECT_NEAR(data_.f_W[0].norm(), 4.0, 1e-12);
  // Three minima on one patch share the stiffness: the total equals one spring.
  params_.max_force_per_minimum_n = 1e3;
  params_.normalise_per_patch = true;
  std::vector<LocalMinimum> patch{minimum(4, 0.005, u), minimum(4, 0.005, u), minimum(4, 0.005, u)};
  patch[1].p_L.x() += 0.01;
  patch[2].p_L.y() += 0.01;
  computeContactForces(params_, model_, fk_, patch, 1e-3, data_);
  EXPECT_NEAR((data_.f_W[0] + data_.f_W[1] + data_.f_W[2]).norm(), params_.stiffness_npm * 0.005, 1e-9);
  // Weighted by depth: springs at 2 mm and 6 mm share as 8:4, total k (8^2 + 4^2)/12 mm.
  patch[1].distance_m = 0.002;
  patch[2].distance_m = 0.006;
  patch[0].distance_m = 0.0099999999;  // entering at d_f: weight ~0, changes nothing
  computeContactForces(params_, model_, fk_, patch, 1e-3, data_);
  EXPECT_NEAR((data_.f_W[0] + data_.f_W[1] + data_.f_W[2]).norm(),
              params_.stiffness_npm * (0.008 * 0.008 + 0.004 * 0.004) / 0.012, 1e-6);
  // A minimum on another object, or far along the link, is its own patch.
  patch[2].object = 1;
  computeContactForces(params_, model_, fk_, patch, 1e-3, data_);
  EXPECT_NEAR(data_.f_W[2].norm(), params_.stiffness_npm * 0.004, 1e-9);
}

TEST_F(ContactForcesTest, HandOnlyRendersHandAndRecordsTheRest) {
  params_.mode = RenderMode::kHandOnly;
  const Vector3d u(0, 0, 1);
  ASSERT_TRUE(isHandLink(model_, model_.tool_link));
  ASSERT_FALSE(isHandLink(model_, 4));
  std::vector<LocalMinimum> minima{minimum(4, 0.002, u), minimum(model_.tool_link, 0.005, u)};
  for (int tick = 0; tick < 250; ++tick) computeContactForces(params_, model_, fk_, minima, 1e-3, data_);
  EXPECT_EQ(data_.active_springs, 1);
  EXPECT_EQ(data_.f_W[0].norm(), 0.0);
  EXPECT_GT(data_.f_W[1].norm(), 0.0);
  const LinkContactRecord& forearm = data_.links[4];
  EXPECT_TRUE(forearm.in_contact);
  EXPECT_NEAR(forearm.depth_m, 0.008, 1e-15);
  EXPECT_NEAR(forearm.contact_duration_s, 0.25, 1e-9);
  EXPECT_EQ(forearm.contact_onsets, 1);
  computeContactTorques(model_, fk_, minima, data_);
  // Only the hand minimum produced torque: equal to its own J^T f.
  arm::PointJacobian J;
  const Vector3d p = fk_.X_WL[static_cast<std::size_t>(model_.tool_link)] * minima[1].p_L;
  arm::computePointJacobian(model_, fk_, model_.tool_link, p, J);
  const Eigen::VectorXd ref = J.topRows<3>().transpose() * data_.f_W[1];
  EXPECT_LE((data_.tau_contact_nm - ref).norm(), 1e-12 * ref.norm());
  // Contact ends: duration resets, totals stay.
  minima[0].distance_m = 0.05;
  computeContactForces(params_, model_, fk_, minima, 1e-3, data_);
  EXPECT_FALSE(data_.links[4].in_contact);
  EXPECT_EQ(data_.links[4].contact_duration_s, 0.0);
  EXPECT_NEAR(data_.links[4].total_contact_s, 0.25, 1e-9);
}

TEST_F(ContactForcesTest, FaultInjectionGivesZeroContactTorque) {
  std::vector<LocalMinimum> minima{minimum(4, 0.002, {0, 0, 1}), minimum(4, 0.003, {0, 0, 1})};
  minima[1].distance_m = std::numeric_limits<double>::quiet_NaN();
  computeContactForces(params_, model_, fk_, minima, 1e-3, data_);
  computeContactTorques(model_, fk_, minima, data_);
  EXPECT_EQ(data_.status.code, core::RtCode::kBadInput);
  EXPECT_EQ(data_.status.faults, core::kFaultNonFiniteInput);
  EXPECT_EQ(data_.tau_contact_nm.norm(), 0.0);
  // Bad link index and more minima than capacity are faults too.
  minima[1] = minimum(99, 0.003, {0, 0, 1});
  computeContactForces(params_, model_, fk_, minima, 1e-3, data_);
  EXPECT_EQ(data_.status.faults, core::kFaultBadIndex);
  computeContactTorques(model_, fk_, minima, data_);
  EXPECT_EQ(data_.tau_contact_nm.norm(), 0.0);
  std::vector<LocalMinimum> too_many(65, minimum(4, 0.002, {0, 0, 1}));
  computeContactForces(params_, model_, fk_, too_many, 1e-3, data_);
  EXPECT_EQ(data_.status.faults, core::kFaultCapacity);
  computeContactForces(params_, model_, fk_, minima, 0.0, data_);  // bad tick period
  EXPECT_EQ(data_.status.faults, core::kFaultOutOfRange);
  // A good tick clears the status.
  minima[1] = minimum(4, 0.003, {0, 0, 1});
  computeContactForces(params_, model_, fk_, minima, 1e-3, data_);
  EXPECT_TRUE(data_.status.ok());
}

TEST_F(ContactForcesTest, ForcesAndTorquesDoNotAllocate) {
  std::vector<LocalMinimum> minima;
  for (int i = 0; i < 64; ++i) minima.push_back(minimum(i % model_.numJoints(), 0.0001 * i, {0, 1, 0}));
  params_.normalise_per_patch = true;
  params_.damping_nspm = 1.0;
  EXPECT_NO_HEAP_ALLOCATION(computeContactForces(params_, model_, fk_, minima, 1e-3, data_));
  EXPECT_NO_HEAP_ALLOCATION(computeContactTorques(model_, fk_, minima, data_));
  EXPECT_GT(data_.active_springs, 0);
}

std::string readText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(HapticsParamsTest, ShippedConfigLoads) {
  const HapticsParams p = loadHapticsParams(defaultHapticsParamsPath());
  EXPECT_EQ(p.mode, RenderMode::kFullArm);
  EXPECT_GT(p.cutoff_m, p.force_threshold_m);
  EXPECT_EQ(p.descent.max_iterations, 16);
}

TEST(HapticsParamsTest, BadValuesNameTheKey) {
  const std::string text = readText(arm::test::sourcePath("config/haptics.yaml"));
  auto expectError = [&](const std::string& from, const std::string& to, const std::string& key) {
    std::string bad = text;
    const auto pos = bad.find(from);
    ASSERT_NE(pos, std::string::npos) << from;
    bad.replace(pos, from.size(), to);
    try {
      (void)parseHapticsParams(bad, "haptics.yaml");
      FAIL() << "expected core::ConfigError for " << to;
    } catch (const core::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("haptics.yaml"), std::string::npos) << e.what();
    }
  };
  expectError("stiffness_npm: 2000.0", "stiffness_npm: -5", "contact.stiffness_npm");
  expectError("cutoff_m: 0.03", "cutoff_m: 0.005", "contact.cutoff_m");
  expectError("mode: full_arm", "mode: elbow_only", "mode");
  expectError("normalise_per_patch: false", "normalise_per_patch: maybe", "normalise_per_patch");
  expectError("max_iterations: 16", "max_iterations: 0", "local_descent.max_iterations");
  expectError("damping_nspm: 0.0", "damping_nspm: 0.0\n  spring_colour: red", "spring_colour");
  expectError("  prune_radius_m: 0.02", "", "prune_radius_m");
}

// L - d_f >= max_link_speed_mps x latency_p99_ms: the shipped 20 mm look-ahead covers 1.5 m/s x
// 2 ms = 3 mm; at 2 m/s x 12 ms = 24 mm it does not, and the error names both figures and the
// keys they come from; without the optional section the defaults apply.
TEST(HapticsParamsTest, LookAheadMustCoverTheLinkSpeedTimesTheSearchLatency) {
  const std::string text = readText(arm::test::sourcePath("config/haptics.yaml"));
  const HapticsParams shipped = parseHapticsParams(text, "haptics.yaml");
  EXPECT_DOUBLE_EQ(minimumCutoffMargin(shipped), shipped.max_link_speed_mps * 1e-3 * shipped.search_latency_p99_ms);
  EXPECT_GE(shipped.cutoff_m - shipped.force_threshold_m, minimumCutoffMargin(shipped));
  std::string slow = text;
  slow.replace(slow.find("latency_p99_ms: 2.0"), 19, "latency_p99_ms: 12.0");
  slow.replace(slow.find("max_link_speed_mps: 1.5"), 23, "max_link_speed_mps: 2.0");
  try {
    (void)parseHapticsParams(slow, "haptics.yaml");
    FAIL() << "a look-ahead of 20 mm against 24 mm must be rejected";
  } catch (const core::ConfigError& e) {
    const std::string what = e.what();
    for (const char* part : {"haptics.yaml", "contact.cutoff_m", "20 mm", "max_link_speed_mps 2 m/s",
                             "latency_p99_ms 12 ms", "= 24 mm", "at least 0.034 m"}) {
      EXPECT_NE(what.find(part), std::string::npos) << part << " in: " << what;
    }
  }
  // The same figures with L raised to 34 mm load.
  std::string raised = slow;
  raised.replace(raised.find("cutoff_m: 0.03"), 14, "cutoff_m: 0.034");
  EXPECT_NO_THROW((void)parseHapticsParams(raised, "haptics.yaml"));
  // Without the section: the defaults (1.5 m/s x 2 ms).
  const HapticsParams defaults = parseHapticsParams(text.substr(0, text.find("\n# Optional")), "haptics.yaml");
  EXPECT_EQ(defaults.search_latency_p99_ms, HapticsParams{}.search_latency_p99_ms);
  EXPECT_EQ(defaults.max_link_speed_mps, HapticsParams{}.max_link_speed_mps);
  for (const auto& [from, to, key] : {std::tuple{"latency_p99_ms: 2.0", "latency_p99_ms: 0", "global_search.latency_p99_ms"},
                                      std::tuple{"max_link_speed_mps: 1.5", "max_link_speed_mps: -1",
                                                 "global_search.max_link_speed_mps"}}) {
    std::string bad = text;
    bad.replace(bad.find(from), std::string(from).size(), to);
    try {
      (void)parseHapticsParams(bad, "haptics.yaml");
      ADD_FAILURE() << to;
    } catch (const core::ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
    }
  }
}

TEST(HapticsParamsTest, MutatedAndTruncatedTextGivesConfigError) {
  const std::string text = readText(arm::test::sourcePath("config/haptics.yaml"));
  std::mt19937 rng(3);
  int errors = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string bad = text;
    std::uniform_int_distribution<std::size_t> pos(0, bad.size() - 1);
    if (trial % 3 == 0) {
      bad.resize(pos(rng));
    } else {
      const char junk[] = {':', '-', '[', '{', 'x', '9', '\n', ' ', '#', '\t'};
      bad[pos(rng)] = junk[std::uniform_int_distribution<int>(0, 9)(rng)];
    }
    try {
      (void)parseHapticsParams(bad, "mutated.yaml");
    } catch (const core::ConfigError& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find("mutated.yaml"), std::string::npos);
    }
  }
  EXPECT_GT(errors, 100);
}

}  // namespace
}  // namespace fullarm::haptics
