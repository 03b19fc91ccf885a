// The accessibility force program and the brace-posture search.
//
// The force program with CLP (dual and primal simplex) beside its peer in the same run: vertex
// enumeration (every set of active inequalities solved, the best feasible vertex kept) on the
// same small program (3 joints, 2 contacts); then the program built and solved on the DTS arm
// model (7 joints, one contact, with and without bracing); then one brace-posture search on a
// bar placed under the forearm (60 evaluations: one haptic query and two programs each).
// Results pass through DoNotOptimize as const values or whole structs: with GCC, the overload for
// a modifiable double left garbage in the variable it was given.
// Speed targets: 1 ms for one program, 2 s for one search.

#include <benchmark/benchmark.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>
#include <vector>

#include "fullarm/accessibility/brace_search.hpp"
#include "fullarm/accessibility/force_lp.hpp"
#include "fullarm/accessibility/human_strength.hpp"
#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/query.hpp"
#include "fullarm/haptics/scene.hpp"

namespace {

using namespace fullarm;
using namespace fullarm::accessibility;

/// A seeded program of 3 joints and 2 frictionless contacts.
ForceProblem smallProblem() {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr int kJoints = 3;
  ForceProblem p;
  p.J_hand = 0.5 * Eigen::MatrixXd::NullaryExpr(3, kJoints, [&] { return u(rng); });
  p.push_direction_W = Eigen::Vector3d(0.3, 0.8, -0.2).normalized();
  for (int c = 0; c < 2; ++c) {
    ForceContact fc;
    fc.J_c = 0.3 * Eigen::MatrixXd::NullaryExpr(3, kJoints, [&] { return u(rng); });
    fc.n_W = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
    p.contacts.push_back(fc);
  }
  p.gravity_nm = Eigen::Vector3d(3.0, -2.0, 1.0);
  p.tau_max_nm = Eigen::Vector3d(60.0, 45.0, 30.0);
  p.tau_min_nm = Eigen::Vector3d(-70.0, -40.0, -25.0);
  return p;
}

/// The peer: the best feasible vertex of G x <= h over every set of n active inequalities
/// (x = s, lambda_1, lambda_2; rows: both torque limits per joint and the bounds x >= 0).
double vertexEnumeration(const ForceProblem& p) {
  const Eigen::Index k = p.J_hand.cols();
  const Eigen::Index n = 1 + static_cast<Eigen::Index>(p.contacts.size());
  Eigen::MatrixXd A(k, n);
  A.col(0) = p.J_hand.transpose() * p.push_direction_W;
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    A.col(static_cast<Eigen::Index>(c) + 1) = p.contacts[c].J_c.transpose() * p.contacts[c].n_W;
  }
  const Eigen::Index m = 2 * k + n;
  Eigen::MatrixXd G(m, n);
  Eigen::VectorXd h(m);
  G.topRows(k) = A;
  h.head(k) = p.tau_max_nm - p.gravity_nm;
  G.middleRows(k, k) = -A;
  h.segment(k, k) = p.gravity_nm - p.tau_min_nm;
  G.bottomRows(n) = -Eigen::MatrixXd::Identity(n, n);
  h.tail(n).setZero();
  double best = -1.0;
  std::vector<int> pick(static_cast<std::size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) pick[static_cast<std::size_t>(i)] = static_cast<int>(i);
  while (true) {
    Eigen::MatrixXd M(n, n);
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      M.row(i) = G.row(pick[static_cast<std::size_t>(i)]);
      r[i] = h[pick[static_cast<std::size_t>(i)]];
    }
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(M);
    if (std::abs(lu.determinant()) > 1e-12) {
      const Eigen::VectorXd x = lu.solve(r);
      if (((G * x - h).array() <= 1e-9).all() && x[0] > best) best = x[0];
    }
    Eigen::Index i = n - 1;
    while (i >= 0 && pick[static_cast<std::size_t>(i)] == m - n + i) --i;
    if (i < 0) break;
    ++pick[static_cast<std::size_t>(i)];
    for (Eigen::Index j = i + 1; j < n; ++j) pick[static_cast<std::size_t>(j)] = pick[static_cast<std::size_t>(j - 1)] + 1;
  }
  return best;
}

void BM_ForceLpClpDual(benchmark::State& state) {
  const ForceProblem p = smallProblem();
  double push = 0.0;
  for (auto _ : state) {
    const ForceLpResult r = solveForceLp(p);
    benchmark::DoNotOptimize(r);
    push = r.push_n;
  }
  state.counters["push_n"] = push;
}
BENCHMARK(BM_ForceLpClpDual);

void BM_ForceLpClpPrimal(benchmark::State& state) {
  const ForceProblem p = smallProblem();
  ForceLpOptions options;
  options.algorithm = LpAlgorithm::kPrimal;
  double push = 0.0;
  for (auto _ : state) {
    const ForceLpResult r = solveForceLp(p, options);
    benchmark::DoNotOptimize(r);
    push = r.push_n;
  }
  state.counters["push_n"] = push;
}
BENCHMARK(BM_ForceLpClpPrimal);

void BM_ForceLpVertexEnumeration(benchmark::State& state) {
  const ForceProblem p = smallProblem();
  double push = 0.0;
  for (auto _ : state) {
    const double v = vertexEnumeration(p);
    benchmark::DoNotOptimize(v);
    push = v;
  }
  state.counters["push_n"] = push;
}
BENCHMARK(BM_ForceLpVertexEnumeration);

/// The DTS arm with the shipped human arm, hand in front of the shoulder.
struct ArmFixture {
  arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  HumanArm human = loadHumanArm(defaultHumanArmPath(), model);
  Eigen::VectorXd q0 = startPosture();
  Eigen::VectorXd startPosture() const {
    Eigen::VectorXd q = model.defaultPosture();
    q[model.jointIndex("R_SFE")] = 0.9;
    q[model.jointIndex("R_SAA")] = -0.4;
    q[model.jointIndex("R_HR")] = 0.2;
    q[model.jointIndex("R_EB")] = 1.2;
    q[model.jointIndex("R_WR")] = 0.0;
    q[model.jointIndex("R_WFE")] = 0.0;
    q[model.jointIndex("R_WAA")] = 0.0;
    return q;
  }
  /// A forearm point a fraction `along` from the elbow to the wrist, world.
  Eigen::Vector3d forearmPoint(const arm::ArmData& fk, double along) const {
    const double d = model.joints[static_cast<std::size_t>(model.forearm_joint)].dh->d_m;
    return arm::pointInWorld(fk, model.forearm_joint, Eigen::Vector3d(0.0, 0.0, -d * (1.0 - along)));
  }
};

void BM_ForceLpArmModel(benchmark::State& state) {
  const ArmFixture f;
  arm::ArmData fk(f.model);
  arm::computeForwardKinematics(f.model, fk, f.q0);
  haptics::LocalMinimum m;
  m.link = f.model.forearm_joint;
  m.p_L = Eigen::Vector3d(0.0, 0.0, -0.24);
  m.distance_m = 0.004;
  m.u_W = -Eigen::Vector3d::UnitZ();
  const std::vector<haptics::LocalMinimum> minima{m};
  const Eigen::Vector3d push = (fk.X_WT.translation() - f.forearmPoint(fk, 1.0)).normalized();
  PushAnalysis a;
  for (auto _ : state) {
    a = analysePush(f.model, f.human, fk, push, minima, {});
    benchmark::DoNotOptimize(a);
  }
  state.counters["braced_n"] = a.braced.push_n;
  state.counters["unbraced_n"] = a.unbraced.push_n;
}
BENCHMARK(BM_ForceLpArmModel)->Unit(benchmark::kMicrosecond);

void BM_BraceSearch(benchmark::State& state) {
  const ArmFixture f;
  arm::ArmData fk(f.model);
  arm::computeForwardKinematics(f.model, fk, f.q0);
  // A bar 15 mm under the forearm's elbow end at the start, across the forearm: the self-motion
  // lowers the elbow onto it.
  const Eigen::Vector3d p_W = f.forearmPoint(fk, 0.15);
  Eigen::Vector3d along = f.forearmPoint(fk, 1.0) - f.forearmPoint(fk, 0.0);
  along.z() = 0.0;
  const Eigen::Vector3d across = Eigen::Vector3d::UnitZ().cross(along).normalized();
  const double yaw_deg = std::atan2(across.y(), across.x()) * 180.0 / std::numbers::pi;
  auto sceneText = [&](const Eigen::Vector3d& c) {
    std::ostringstream yaml;
    yaml.precision(17);
    yaml << "schema_version: 1\nname: brace_bar\narm:\n  shoulder_m: [0.0, 0.0, 1.4]\nobjects:\n  - name: bar\n"
         << "    pose: {translation_m: [" << c.x() << ", " << c.y() << ", " << c.z() << "], rpy_deg: [0.0, 0.0, "
         << yaw_deg << "]}\n    shape: {type: box, size_m: [0.5, 0.03, 0.03], max_edge_m: 0.02}\n";
    return yaml.str();
  };
  // The bar's centre in the arm world W, then in the scene frame S (X_SW from the arm block).
  const Eigen::Vector3d c_W(p_W.x(), p_W.y(), p_W.z() - 0.04 - 0.015 - 0.015);
  const Eigen::Isometry3d X_SW = haptics::armBasePose(haptics::parseScene(sceneText(c_W), "brace_bar.yaml"), f.model);
  const std::string yaml = sceneText(X_SW * c_W);
  const haptics::Scene scene = haptics::parseScene(yaml, "brace_bar.yaml");
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, f.model);
  const std::unique_ptr<haptics::GlobalSearch> search = haptics::makeGlobalSearch(haptics::SearchKind::kSnch, world);
  const haptics::HapticsParams params = haptics::loadHapticsParams(haptics::defaultHapticsParamsPath());
  const Eigen::Vector3d push = (fk.X_WT.translation() - f.forearmPoint(fk, 1.0)).normalized();
  BraceSearchOptions options;
  options.max_evaluations = 60;
  BraceSearchResult r;
  for (auto _ : state) {
    r = searchBracePosture(f.model, f.human, world, *search, params, f.q0, push, options);
    benchmark::DoNotOptimize(r);
  }
  state.counters["start_n"] = r.start.unbraced.push_n;
  state.counters["best_n"] = r.bestPush();
  state.counters["evaluations"] = r.evaluations;
}
BENCHMARK(BM_BraceSearch)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
