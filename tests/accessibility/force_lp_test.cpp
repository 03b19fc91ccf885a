// The force linear program against independent answers: vertex enumeration on small random
// programs, a planar two-link arm solved by hand, the statuses CLP reports, and the program
// built on the DTS arm model against the haptics module's tailored force Jacobians.

#include "fullarm/accessibility/force_lp.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include "arm_test_util.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/contact_forces.hpp"

namespace fullarm::accessibility {
namespace {

constexpr double kTolerance_n = 1e-6;

// ---------------------------------------------------------------------------------------------
// Brute force: the program in the variables x = (s, [f1, f2], lambda_1 .. lambda_m), written as
// inequalities G x <= h (joint limits both ways and the variable bounds). Every vertex is the
// solution of some set of n active inequalities; the optimum of a bounded feasible program is
// the best feasible vertex. Friction and off-axis columns are built here independently of the
// solver (the pyramid edge n + mu t with t along +-t1, +-t2 of any orthonormal completion).

struct BruteProgram {
  Eigen::MatrixXd A;   // k x n joint torque per unit of each variable
  Eigen::VectorXd lo;  // k: tau_min - g
  Eigen::VectorXd hi;  // k: tau_max - g
  Eigen::VectorXd var_lo;
  Eigen::VectorXd var_hi;
};

void completeBasis(const Eigen::Vector3d& d, Eigen::Vector3d& a, Eigen::Vector3d& b) {
  // Any orthonormal completion gives the same program: a rotated pyramid is not the same set,
  // so the test uses the same rule as the header documents only for the frictionless and
  // off-axis cases (where the set is rotation-invariant), and the solver's pyramid for mu > 0
  // is checked through its edges below.
  const Eigen::Vector3d seed = std::abs(d.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  a = (seed - seed.dot(d) * d).normalized();
  b = d.cross(a);
}

BruteProgram bruteProgram(const ForceProblem& p, const ForceLpOptions& o, double s_max) {
  std::vector<Eigen::VectorXd> cols;
  std::vector<double> vlo;
  std::vector<double> vhi;
  cols.push_back(p.J_hand.transpose() * p.push_direction_W);
  vlo.push_back(0.0);
  vhi.push_back(s_max);
  if (o.off_axis_force_max_n > 0.0) {
    Eigen::Vector3d a;
    Eigen::Vector3d b;
    completeBasis(p.push_direction_W, a, b);
    for (const Eigen::Vector3d& e : {a, b}) {
      cols.push_back(p.J_hand.transpose() * e);
      vlo.push_back(-o.off_axis_force_max_n);
      vhi.push_back(o.off_axis_force_max_n);
    }
  }
  for (const ForceContact& c : p.contacts) {
    if (o.friction_mu == 0.0) {
      cols.push_back(c.J_c.transpose() * c.n_W);
      vlo.push_back(0.0);
      vhi.push_back(std::numeric_limits<double>::infinity());
    } else {
      Eigen::Vector3d a;
      Eigen::Vector3d b;
      completeBasis(c.n_W, a, b);
      for (const Eigen::Vector3d& t : {a, Eigen::Vector3d(-a), b, Eigen::Vector3d(-b)}) {
        cols.push_back(c.J_c.transpose() * (c.n_W + o.friction_mu * t));
        vlo.push_back(0.0);
        vhi.push_back(std::numeric_limits<double>::infinity());
      }
    }
  }
  BruteProgram b;
  b.A.resize(p.J_hand.cols(), static_cast<Eigen::Index>(cols.size()));
  for (std::size_t i = 0; i < cols.size(); ++i) b.A.col(static_cast<Eigen::Index>(i)) = cols[i];
  b.lo = p.tau_min_nm - p.gravity_nm;
  b.hi = p.tau_max_nm - p.gravity_nm;
  b.var_lo = Eigen::Map<Eigen::VectorXd>(vlo.data(), static_cast<Eigen::Index>(vlo.size()));
  b.var_hi = Eigen::Map<Eigen::VectorXd>(vhi.data(), static_cast<Eigen::Index>(vhi.size()));
  return b;
}

/// Largest s over the vertices, or nullopt when no vertex is feasible.
std::optional<double> bruteForceMaxPush(const BruteProgram& b) {
  const Eigen::Index n = b.A.cols();
  const Eigen::Index k = b.A.rows();
  // Inequalities G x <= h.
  std::vector<Eigen::RowVectorXd> G;
  std::vector<double> h;
  for (Eigen::Index j = 0; j < k; ++j) {
    G.push_back(b.A.row(j));
    h.push_back(b.hi[j]);
    G.push_back(-b.A.row(j));
    h.push_back(-b.lo[j]);
  }
  for (Eigen::Index i = 0; i < n; ++i) {
    Eigen::RowVectorXd e = Eigen::RowVectorXd::Zero(n);
    e[i] = 1.0;
    if (std::isfinite(b.var_hi[i])) {
      G.push_back(e);
      h.push_back(b.var_hi[i]);
    }
    G.push_back(-e);
    h.push_back(-b.var_lo[i]);
  }
  const auto m = static_cast<int>(G.size());
  std::optional<double> best;
  std::vector<int> pick(static_cast<std::size_t>(n));
  // Every n-subset of the m inequalities, in lexicographic order.
  for (int i = 0; i < n; ++i) pick[static_cast<std::size_t>(i)] = i;
  while (true) {
    Eigen::MatrixXd M(n, n);
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      M.row(i) = G[static_cast<std::size_t>(pick[static_cast<std::size_t>(i)])];
      r[i] = h[static_cast<std::size_t>(pick[static_cast<std::size_t>(i)])];
    }
    const Eigen::FullPivLU<Eigen::MatrixXd> lu(M);
    if (lu.isInvertible()) {
      const Eigen::VectorXd x = lu.solve(r);
      bool feasible = true;
      for (int i = 0; i < m && feasible; ++i) {
        feasible = G[static_cast<std::size_t>(i)].dot(x) <= h[static_cast<std::size_t>(i)] + 1e-9 * (1.0 + std::abs(h[static_cast<std::size_t>(i)]));
      }
      if (feasible && (!best || x[0] > *best)) best = x[0];
    }
    int i = static_cast<int>(n) - 1;
    while (i >= 0 && pick[static_cast<std::size_t>(i)] == m - static_cast<int>(n) + i) --i;
    if (i < 0) break;
    ++pick[static_cast<std::size_t>(i)];
    for (int j = i + 1; j < n; ++j) pick[static_cast<std::size_t>(j)] = pick[static_cast<std::size_t>(j - 1)] + 1;
  }
  return best;
}

ForceProblem randomProblem(std::mt19937& rng, int joints, int contacts) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> strength(20.0, 90.0);
  ForceProblem p;
  p.J_hand = 0.5 * Eigen::MatrixXd::NullaryExpr(3, joints, [&] { return u(rng); });
  p.push_direction_W = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
  for (int c = 0; c < contacts; ++c) {
    ForceContact fc;
    fc.J_c = 0.3 * Eigen::MatrixXd::NullaryExpr(3, joints, [&] { return u(rng); });
    fc.n_W = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    p.contacts.push_back(fc);
  }
  p.gravity_nm = 5.0 * Eigen::VectorXd::NullaryExpr(joints, [&] { return u(rng); });
  p.tau_max_nm = Eigen::VectorXd::NullaryExpr(joints, [&] { return strength(rng); });
  p.tau_min_nm = -Eigen::VectorXd::NullaryExpr(joints, [&] { return strength(rng); });
  return p;
}

void expectMatchesBruteForce(const ForceProblem& p, const ForceLpOptions& o, const std::string& label) {
  constexpr double kBigPush_n = 1e6;  // a push this large stands for "unbounded" in the enumeration
  const ForceLpResult r = solveForceLp(p, o);
  const std::optional<double> brute = bruteForceMaxPush(bruteProgram(p, o, kBigPush_n));
  if (!brute) {
    EXPECT_EQ(r.status, ForceStatus::kCannotHold) << label;
    return;
  }
  if (*brute >= kBigPush_n - 1e-3) {
    EXPECT_EQ(r.status, ForceStatus::kUnbounded) << label;
    return;
  }
  ASSERT_EQ(r.status, ForceStatus::kOptimal) << label << ": " << r.message;
  EXPECT_NEAR(r.push_n, *brute, kTolerance_n) << label;
  // The reported torques are within the limits and balance the reported forces.
  Eigen::VectorXd tau = p.gravity_nm + p.J_hand.transpose() * r.hand_force_W;
  for (std::size_t c = 0; c < p.contacts.size(); ++c) tau += p.contacts[c].J_c.transpose() * r.contacts[c].force_W;
  EXPECT_LT((tau - r.tau_nm).norm(), 1e-8) << label;
  for (Eigen::Index j = 0; j < tau.size(); ++j) {
    EXPECT_LE(r.tau_nm[j], p.tau_max_nm[j] + 1e-7) << label;
    EXPECT_GE(r.tau_nm[j], p.tau_min_nm[j] - 1e-7) << label;
  }
  for (const ContactForce& cf : r.contacts) EXPECT_GE(cf.normal_n, -1e-9) << label;
  // At an optimum some limit binds (otherwise the push could grow).
  EXPECT_FALSE(r.active.empty()) << label;
}

TEST(ForceLp, MatchesVertexEnumerationOnSmallPrograms) {
  std::mt19937 rng(11);
  int optimal = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const int joints = 2 + trial % 2;
    const int contacts = trial % 3;
    const ForceProblem p = randomProblem(rng, joints, contacts);
    expectMatchesBruteForce(p, {}, "trial " + std::to_string(trial));
    if (solveForceLp(p).status == ForceStatus::kOptimal) ++optimal;
  }
  EXPECT_GE(optimal, 30);  // the cases are mostly bounded and feasible
}

TEST(ForceLp, MatchesVertexEnumerationWithFrictionAndOffAxisForce) {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 20; ++trial) {
    const ForceProblem p = randomProblem(rng, 2 + trial % 2, 1);
    ForceLpOptions friction;
    friction.friction_mu = 0.4;
    expectMatchesBruteForce(p, friction, "friction trial " + std::to_string(trial));
    ForceLpOptions off_axis;
    off_axis.off_axis_force_max_n = 15.0;
    expectMatchesBruteForce(p, off_axis, "off-axis trial " + std::to_string(trial));
  }
}

TEST(ForceLp, DualAndPrimalSimplexAgree) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const ForceProblem p = randomProblem(rng, 3, 2);
    ForceLpOptions primal;
    primal.algorithm = LpAlgorithm::kPrimal;
    const ForceLpResult a = solveForceLp(p);
    const ForceLpResult b = solveForceLp(p, primal);
    ASSERT_EQ(a.status, b.status) << trial;
    if (a.status == ForceStatus::kOptimal) {
      EXPECT_NEAR(a.push_n, b.push_n, kTolerance_n) << trial;
    }
  }
}

// ---------------------------------------------------------------------------------------------
// A planar two-link arm in the x-y plane, joints about +z at the origin and the elbow, gravity
// along -y, worked by hand.
//   l1 = 0.30 m, l2 = 0.25 m, q1 = 0, q2 = 90 deg: elbow at (0.30, 0), hand at (0.30, 0.25).
//   Hand Jacobian J = [[-l1 s1 - l2 s12, -l2 s12], [l1 c1 + l2 c12, l2 c12]] = [[-0.25, -0.25],
//   [0.30, 0]] (rows x, y).
//   Point masses m1 = 2 kg at mid-link 1 (0.15, 0), m2 = 1.5 kg at mid-link 2 (0.30, 0.125):
//   V = g (m1 y1 + m2 y2), g1 = dV/dq1 = g (m1 l1/2 c1 + m2 (l1 c1 + l2/2 c12)) = 9.81 (0.30 +
//   0.45) = 7.3575 N m; g2 = g m2 l2/2 c12 = 0.
//   Push along d = +x: tau = J^T d s + g = (-0.25 s + 7.3575, -0.25 s).
//   Limits: joint 1 in [-20, 60] N m, joint 2 in [-50, 30] N m.
//   Unbraced: joint 1 gives -0.25 s + 7.3575 >= -20, s <= 109.43; joint 2 gives s <= 200.
//   So s* = 27.3575 / 0.25 = 109.43 N with joint 1 at its lower limit.
//   Braced: a ledge just above the elbow; the elbow pushes up into it, n = +y at (0.30, 0):
//   J_c = [[0, 0], [0.30, 0]], J_c^T n = (0.30, 0), tau1 = -0.25 s + 7.3575 + 0.30 lambda.
//   lambda >= 0 lifts joint 1 off its limit (up to tau1 <= 60), so joint 2 binds: s* = 200 N
//   with joint 2 at its lower limit, a leverage of 200 / 109.43 = 1.83.

constexpr double kL1 = 0.30;
constexpr double kL2 = 0.25;

ForceProblem planarTwoLink(double q2_rad, const Eigen::Vector3d& push) {
  const double s1 = 0.0;
  const double c1 = 1.0;
  const double s12 = std::sin(q2_rad);
  const double c12 = std::cos(q2_rad);
  ForceProblem p;
  p.J_hand = Eigen::MatrixXd::Zero(3, 2);
  p.J_hand << -kL1 * s1 - kL2 * s12, -kL2 * s12, kL1 * c1 + kL2 * c12, kL2 * c12, 0.0, 0.0;
  p.push_direction_W = push;
  const double g = 9.81;
  p.gravity_nm = Eigen::Vector2d(g * (2.0 * kL1 / 2.0 * c1 + 1.5 * (kL1 * c1 + kL2 / 2.0 * c12)), g * 1.5 * kL2 / 2.0 * c12);
  p.tau_min_nm = Eigen::Vector2d(-20.0, -50.0);
  p.tau_max_nm = Eigen::Vector2d(60.0, 30.0);
  return p;
}

TEST(ForceLp, PlanarTwoLinkMatchesTheHandDerivation) {
  const ForceProblem p = planarTwoLink(std::numbers::pi / 2.0, Eigen::Vector3d::UnitX());
  ASSERT_NEAR(p.gravity_nm[0], 7.3575, 1e-12);
  const ForceLpResult r = solveForceLp(p);
  ASSERT_EQ(r.status, ForceStatus::kOptimal) << r.message;
  EXPECT_NEAR(r.push_n, 27.3575 / 0.25, kTolerance_n);
  ASSERT_EQ(r.active.size(), 1U);
  EXPECT_EQ(r.active[0].joint, 0);
  EXPECT_FALSE(r.active[0].upper);
}

TEST(ForceLp, BracingTheElbowRaisesThePushAsDerived) {
  ForceProblem p = planarTwoLink(std::numbers::pi / 2.0, Eigen::Vector3d::UnitX());
  ForceContact ledge;
  ledge.J_c = Eigen::MatrixXd::Zero(3, 2);
  ledge.J_c(1, 0) = kL1;  // the elbow point moves along +y with joint 1 only
  ledge.n_W = Eigen::Vector3d::UnitY();
  p.contacts.push_back(ledge);
  const ForceLpResult braced = solveForceLp(p);
  ASSERT_EQ(braced.status, ForceStatus::kOptimal) << braced.message;
  EXPECT_NEAR(braced.push_n, 200.0, kTolerance_n);
  // Joint 2 binds at its lower limit (joint 1 may sit at either end of lambda's range too).
  ASSERT_FALSE(braced.active.empty());
  EXPECT_EQ(braced.active.back().joint, 1);
  EXPECT_FALSE(braced.active.back().upper);
  // lambda must lift tau1 = -50 + 7.3575 + 0.30 lambda into [-20, 60].
  EXPECT_GE(0.30 * braced.contacts[0].normal_n, -20.0 + 50.0 - 7.3575 - 1e-6);
  EXPECT_LE(0.30 * braced.contacts[0].normal_n, 60.0 + 50.0 - 7.3575 + 1e-6);
  // A ledge below the elbow (n = -y) only adds load on joint 1's weak side: no gain.
  p.contacts[0].n_W = -Eigen::Vector3d::UnitY();
  EXPECT_NEAR(solveForceLp(p).push_n, 27.3575 / 0.25, kTolerance_n);
}

TEST(ForceLp, ReportsAnArmThatCannotHoldItselfAsInfeasible) {
  // Pushing along -x needs joint 1 at 7.3575 + 0.25 s >= 7.3575 N m; a limit of 5 N m cannot
  // even hold the arm's weight.
  ForceProblem p = planarTwoLink(std::numbers::pi / 2.0, -Eigen::Vector3d::UnitX());
  p.tau_max_nm[0] = 5.0;
  const ForceLpResult r = solveForceLp(p);
  EXPECT_EQ(r.status, ForceStatus::kCannotHold);
  EXPECT_TRUE(std::isnan(r.push_n));
  EXPECT_NE(r.message.find("infeasible"), std::string::npos);
}

TEST(ForceLp, ReportsAPushThroughTheJointsAsUnbounded) {
  // Arm stretched along x (q2 = 0): J = [[0, 0], [0.55, 0.25]]; a push along x loads no joint.
  const ForceProblem p = planarTwoLink(0.0, Eigen::Vector3d::UnitX());
  const ForceLpResult r = solveForceLp(p);
  EXPECT_EQ(r.status, ForceStatus::kUnbounded);
  EXPECT_TRUE(std::isnan(r.push_n));
  ForceLpOptions primal;
  primal.algorithm = LpAlgorithm::kPrimal;
  EXPECT_EQ(solveForceLp(p, primal).status, ForceStatus::kUnbounded);
}

TEST(ForceLp, RoundingNoiseInAJacobianDoesNotChangeTheOptimum) {
  // A contact column with an entry of 1e-17 (rounding noise of a Jacobian) beside one without.
  ForceProblem p = planarTwoLink(std::numbers::pi / 2.0, Eigen::Vector3d::UnitX());
  ForceContact ledge;
  ledge.J_c = Eigen::MatrixXd::Zero(3, 2);
  ledge.J_c(1, 0) = kL1;
  ledge.n_W = Eigen::Vector3d::UnitY();
  p.contacts.push_back(ledge);
  const double clean = solveForceLp(p).push_n;
  p.contacts[0].J_c(1, 1) = -1.04e-17;
  EXPECT_NEAR(solveForceLp(p).push_n, clean, kTolerance_n);
  EXPECT_NEAR(clean, 200.0, kTolerance_n);
  // Given to CLP, the entry makes it report s = 0 as optimal; the optimality check refuses that
  // answer: the result is the true optimum or a reported failure, never a wrong optimum.
  ForceLpOptions keep;
  keep.drop_tolerance = 0.0;
  const ForceLpResult r = solveForceLp(p, keep);
  if (r.status == ForceStatus::kOptimal) {
    EXPECT_NEAR(r.push_n, clean, kTolerance_n);
  } else {
    EXPECT_EQ(r.status, ForceStatus::kSolverFailed);
    EXPECT_TRUE(std::isnan(r.push_n));
    EXPECT_NE(r.message.find("optimality check"), std::string::npos) << r.message;
  }
}

TEST(ForceLp, RejectsInconsistentPrograms) {
  ForceProblem p = planarTwoLink(std::numbers::pi / 2.0, Eigen::Vector3d::UnitX());
  p.push_direction_W = Eigen::Vector3d(2.0, 0.0, 0.0);
  EXPECT_THROW((void)solveForceLp(p), std::invalid_argument);
  p = planarTwoLink(std::numbers::pi / 2.0, Eigen::Vector3d::UnitX());
  p.tau_min_nm[1] = 40.0;
  EXPECT_THROW((void)solveForceLp(p), std::invalid_argument);
  p = planarTwoLink(std::numbers::pi / 2.0, Eigen::Vector3d::UnitX());
  p.gravity_nm.resize(3);
  EXPECT_THROW((void)solveForceLp(p), std::invalid_argument);
}

// ---------------------------------------------------------------------------------------------
// On the DTS arm model: the torques the program reports equal those of the haptics module's
// tailored force Jacobians (Eq. (1)-(2)) for the same hand and contact forces, plus g_human.

TEST(ForceLp, ArmModelProgramAgreesWithTheTailoredForceJacobians) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const HumanArm human = loadHumanArm(defaultHumanArmPath(), model);
  arm::ArmData fk(model);
  Eigen::VectorXd q = model.defaultPosture();
  q[model.jointIndex("R_SFE")] = 0.6;
  q[model.jointIndex("R_EB")] = 1.4;
  arm::computeForwardKinematics(model, fk, q);
  // One contact under the forearm's middle (link of R_WR), pushing down on the structure.
  haptics::LocalMinimum m;
  m.link = model.forearm_joint;
  m.p_L = Eigen::Vector3d(0.0, 0.0, -0.14);
  m.distance_m = 0.002;
  m.u_W = -Eigen::Vector3d::UnitZ();
  haptics::LocalMinimum far = m;
  far.distance_m = 0.5;  // beyond the contact distance: not a contact
  const std::vector<haptics::LocalMinimum> minima{m, far};
  const Eigen::Vector3d d = Eigen::Vector3d(1.0, 0.0, -1.0).normalized();
  const PushAnalysis a = analysePush(model, human, fk, d, minima, {});
  ASSERT_EQ(a.contacts.size(), 1U);
  ASSERT_EQ(a.braced.status, ForceStatus::kOptimal) << a.braced.message;
  ASSERT_EQ(a.unbraced.status, ForceStatus::kOptimal) << a.unbraced.message;
  EXPECT_GE(a.braced.push_n, a.unbraced.push_n - kTolerance_n);  // bracing never lowers the push

  Eigen::VectorXd tau = computeHumanGravityTorques(model, human, fk);
  haptics::addTailoredJacobianTorques(model, fk, model.tool_link, fk.X_WT.translation(), a.braced.hand_force_W, tau);
  haptics::addTailoredJacobianTorques(model, fk, m.link, arm::pointInWorld(fk, m.link, m.p_L),
                                      a.braced.contacts[0].force_W, tau);
  const std::vector<int> joints = human.jointIndices();
  for (std::size_t i = 0; i < joints.size(); ++i) {
    EXPECT_NEAR(a.braced.tau_nm[static_cast<Eigen::Index>(i)], tau[joints[i]], 1e-9) << "joint " << joints[i];
  }
}

}  // namespace
}  // namespace fullarm::accessibility
