// The 1 kHz haptic tick for 64 tracked minima: forward kinematics, local descent, contact
// springs and tailored-Jacobian torques (+ gravity), side by side with two peers on the same
// scene and configuration: a fresh SNCH global search, and FCL's capsule-mesh distance (global
// minimum only) on the same link x object pairs. The links are the arm model's exact capsules;
// BM_Haptics_LocalTick64FacetedLinks runs the same tick with the links as 16 x 4 faceted meshes
// (the mesh-link path).
//
// Scene: the default DTS arm at its default posture resting on three ledges: dense boxes
// (1 cm triangles, +-1.5 mm random relief) whose top faces run parallel to the upper arm, forearm and hand capsules,
// 6 mm below them (the flat contact that floods a minimum-distance search). Each iteration starts
// from the same 64 tracked minima found at q0 (cutoff 6 cm, pruning radius 2 mm) and updates
// them at q1 = q0 + delta on every joint: delta = 0.057 deg (one 1 ms tick at 1 rad/s, Arg 57)
// or 0.2 deg (3.5 rad/s, Arg 200). The median and p99 of the per-iteration time
// are reported as counters (median_us, p99_us), measured with steady_clock around each tick.

#include <benchmark/benchmark.h>

#include <fcl/narrowphase/distance.h>
#include <algorithm>
#include <chrono>
#include <memory>
#include <random>
#include <vector>

#include "fcl_mesh.hpp"  // tests/haptics: the FCL peer's mesh
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/local_descent.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "resting_arm_scene.hpp"

namespace {

using namespace fullarm;
using namespace fullarm::haptics;
using fullarm::haptics::test::fclCapsule;
using fullarm::haptics::test::fclModel;
using namespace fullarm::bench;

struct Scene {
  arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  CollisionWorld world{model};
  CollisionWorld faceted{model};  // the same objects, the links as 16 x 4 meshes
  Eigen::VectorXd q0 = model.defaultPosture();
  std::vector<LocalMinimum> baseline;
  std::vector<LocalMinimum> faceted_baseline;
  HapticsParams params;

  Scene() {
    arm::ArmData fk(model);
    arm::computeForwardKinematics(model, fk, q0);
    addLedges(model, fk, {&world, &faceted});
    for (int l = 0; l < model.numJoints(); ++l) {
      if (faceted.linkShape(l) == LinkShape::kCapsule) faceted.setLinkMesh(l, makeLinkCapsuleMesh(model, l, 16, 4));
    }
    baseline = baselineMinima(world, fk);
    faceted_baseline = baselineMinima(faceted, fk);
  }
};

Scene& scene() {
  static Scene s;
  return s;
}

void localTick64(benchmark::State& state, const LocalDescentParams& descent, bool faceted = false) {
  Scene& s = scene();
  const CollisionWorld& world = faceted ? s.faceted : s.world;
  const std::vector<LocalMinimum>& baseline = faceted ? s.faceted_baseline : s.baseline;
  arm::ArmData fk(s.model);
  ContactData data(s.model, static_cast<int>(kMinima));
  std::vector<LocalMinimum> minima(baseline);
  const Eigen::VectorXd q1 = motion(s.q0, state);
  std::vector<double> us;
  us.reserve(1 << 20);
  int kept = 0;
  LocalDescentStats stats;
  for (auto _ : state) {
    std::copy(baseline.begin(), baseline.end(), minima.begin());
    const auto t0 = std::chrono::steady_clock::now();
    arm::computeForwardKinematics(s.model, fk, q1);
    kept = updateMinimaLocalDescent(world, fk, minima, descent, &stats);
    const std::span<const LocalMinimum> live(minima.data(), static_cast<std::size_t>(kept));
    computeContactForces(s.params, s.model, fk, live, 1e-3, data);
    computeContactTorques(s.model, fk, live, data);
    arm::computeGravityTorquesAtKinematics(s.model, fk);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(data.tau_contact_nm.data());
    benchmark::DoNotOptimize(fk.tau_gravity.data());
    if (us.size() < us.capacity()) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  state.counters["minima_kept"] = kept;
  state.counters["active_springs"] = data.active_springs;
  state.counters["pairs_evaluated"] = stats.evaluated;
  state.counters["rescreened"] = stats.rescreened;
  state.counters["cone_rejected"] = stats.cone_rejected;
  state.counters["screened"] = stats.screened;
  reportPercentiles(state, us);
}

void BM_Haptics_LocalTick64(benchmark::State& state) {
  localTick64(state, scene().params.descent);
}
BENCHMARK(BM_Haptics_LocalTick64)->Arg(57)->Arg(200);

// The same tick with the links as faceted 16 x 4 capsule meshes (the mesh-link path).
void BM_Haptics_LocalTick64FacetedLinks(benchmark::State& state) {
  localTick64(state, scene().params.descent, true);
}
BENCHMARK(BM_Haptics_LocalTick64FacetedLinks)->Arg(57)->Arg(200);

// Peer: the same tick with the neighbour-rejection cones off (every neighbour of a closest
// vertex or edge screened one by one): the path before the cones, same minima.
void BM_Peer_LocalTick64NoCones(benchmark::State& state) {
  LocalDescentParams descent = scene().params.descent;
  descent.cone_screening = false;
  localTick64(state, descent);
}
BENCHMARK(BM_Peer_LocalTick64NoCones)->Arg(57)->Arg(200);

// Machine-noise reference for the tick's tail: every tick iteration above does identical work
// (same baseline, same q1, same memory), so its spread is the machine's, not the algorithm's.
// This loop does a fixed, similar amount of the same kind of work (closest points of fixed
// triangle pairs, a few kB of data) and is timed the same way: a p99/median here close to the
// tick's means the tick's tail is preemption, interrupts and cache effects of the machine.
void BM_Peer_FixedWorkNoiseFloor(benchmark::State& state) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> c(-0.01, 0.01);
  std::vector<std::pair<PreparedTriangle, PreparedTriangle>> pairs;
  auto point = [&](double z) { return Eigen::Vector3d(c(rng), c(rng), z + c(rng)); };
  for (int i = 0; i < 64; ++i) {
    pairs.emplace_back(prepareTriangle(point(0.0), point(0.0), point(0.0)),
                       prepareTriangle(point(0.03), point(0.03), point(0.03)));
  }
  const int calls = static_cast<int>(state.range(0));
  std::vector<double> us;
  us.reserve(1 << 20);
  double sum = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    for (int k = 0; k < calls; ++k) {
      const auto& [a, b] = pairs[static_cast<std::size_t>(k) % pairs.size()];
      sum += closestPointsTriangleTriangle(a, b).distance_m;
    }
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(sum);
    if (us.size() < us.capacity()) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  reportPercentiles(state, us);
}
BENCHMARK(BM_Peer_FixedWorkNoiseFloor)->Arg(250);

void BM_Peer_FreshSnchSearch(benchmark::State& state) {
  Scene& s = scene();
  arm::ArmData fk(s.model);
  arm::computeForwardKinematics(s.model, fk, motion(s.q0, state));
  SnchGlobalSearch search;
  std::vector<LocalMinimum> out;
  std::vector<double> us;
  us.reserve(1 << 16);
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    search.search(s.world, fk, 0.06, kPruneRadius_m, out);
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(out.data());
    if (us.size() < us.capacity()) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  state.counters["minima"] = static_cast<double>(out.size());
  state.counters["node_pairs"] = static_cast<double>(search.lastStats().node_pairs_visited);
  state.counters["tri_pairs"] = static_cast<double>(search.lastStats().triangle_pairs_tested);
  state.counters["cone_pruned"] = static_cast<double>(search.lastStats().pruned_by_cone);
  reportPercentiles(state, us);
}
BENCHMARK(BM_Peer_FreshSnchSearch)->Arg(57);

// FCL computes one (global) minimum per pair: here every link x object pair that holds one of
// the 64 tracked minima, at q1.
void BM_Peer_FclDistanceSamePairs(benchmark::State& state) {
  Scene& s = scene();
  arm::ArmData fk(s.model);
  arm::computeForwardKinematics(s.model, fk, motion(s.q0, state));
  std::vector<std::pair<int, int>> pairs;
  for (const auto& m : s.baseline) pairs.emplace_back(m.link, m.object);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  std::vector<test::FclCapsule> links(static_cast<std::size_t>(s.model.numJoints()));
  std::vector<std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>> objects;
  for (int o = 0; o < s.world.numObjects(); ++o) objects.push_back(fclModel(s.world.object(o).mesh));
  for (const auto& [l, o] : pairs) {
    if (!links[static_cast<std::size_t>(l)].shape)
      links[static_cast<std::size_t>(l)] = fclCapsule(s.world.linkCapsule(l));
  }
  std::vector<double> us;
  us.reserve(1 << 16);
  double sum = 0.0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    for (const auto& [l, o] : pairs) {
      const test::FclCapsule& c = links[static_cast<std::size_t>(l)];
      fcl::CollisionObjectd a(c.shape, fk.X_WL[static_cast<std::size_t>(l)] * c.X_LC);
      fcl::CollisionObjectd b(objects[static_cast<std::size_t>(o)], s.world.object(o).X_WO);
      fcl::DistanceRequestd req;
      fcl::DistanceResultd res;
      fcl::distance(&a, &b, req, res);
      sum += res.min_distance;
    }
    const auto t1 = std::chrono::steady_clock::now();
    benchmark::DoNotOptimize(sum);
    if (us.size() < us.capacity()) us.push_back(std::chrono::duration<double, std::micro>(t1 - t0).count());
  }
  state.counters["pairs"] = static_cast<double>(pairs.size());
  reportPercentiles(state, us);
}
BENCHMARK(BM_Peer_FclDistanceSamePairs)->Arg(57);

}  // namespace

BENCHMARK_MAIN();
