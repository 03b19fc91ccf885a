// Global search of the 7-link DTS arm against scenes/valve_wall.yaml (DRC valve walls, wheel
// valve, truss, opening frame): SNCH vs the Bullet alternative search, which returns the same
// minima (checked before timing), in the same run; then both on the same scene with every
// object subdivided to ~100k and ~1M triangles (midpoint subdivision keeps the surfaces).
// Counters: minima, triangle pairs given to the exact test, node pairs visited and pruned
// (by distance, cone, and for the convex link capsules the per-triangle bound or GJK axis), and
// the GJK calls of the convex-link path.
//
// Hierarchies at scale (BM_Hierarchy_*): the DRC truss subdivided four times (1,123,072
// triangles, an open CAD mesh with rims), its SNCH tree built, tree and neighbour-rejection cones
// built, and both loaded from a saved file (hierarchy_cache.hpp); the peer builds FCL's OBBRSS
// BVH of the same mesh.
//
// build/release/bench/haptics_global_bench --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// build/release/bench/haptics_global_bench --benchmark_filter='Hierarchy|FclBvh' --benchmark_repetitions=3
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <stdexcept>

#include "fcl_mesh.hpp"  // tests/haptics: the FCL peer's mesh
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/bullet_search.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/hierarchy_cache.hpp"
#include "fullarm/haptics/mesh_import.hpp"
#include "fullarm/haptics/mesh_subdivision.hpp"
#include "fullarm/haptics/scene.hpp"

namespace {

using namespace fullarm;

constexpr double kCutoff_m = 0.03;  // config/haptics.yaml
constexpr double kPruneRadius_m = 0.02;

std::filesystem::path sourceFile(const char* relative) {
  return std::filesystem::path(FULLARM_SOURCE_DIR) / relative;
}

struct Setup {
  arm::ArmModel model = arm::loadArmModel(sourceFile("config/dts_master.yaml"));
  haptics::Scene scene = haptics::loadScene(sourceFile("scenes/valve_wall.yaml"));
  arm::ArmData fk{model};
  Setup() { arm::computeForwardKinematics(model, fk, haptics::scenePosture(scene, "reach_valve", model)); }
};

Setup& setup() {
  static Setup s;
  return s;
}

// The scene with its objects midpoint-subdivided: `large` levels for the three wall panels and
// the truss, `small` levels for the rest (x 4 triangles per level).
haptics::Scene subdivided(int small, int large) {
  haptics::Scene scene = setup().scene;
  for (haptics::SceneObject& o : scene.objects) {
    const bool big = o.mesh_file.filename() == "five_dice_wall.dae" || o.mesh_file.filename() == "truss.dae";
    o.mesh = haptics::subdivideMidpoint(o.mesh, big ? large : small);
  }
  return scene;
}

void checkSameMinima(const std::vector<haptics::LocalMinimum>& a, const std::vector<haptics::LocalMinimum>& b) {
  bool same = a.size() == b.size();
  for (std::size_t i = 0; same && i < a.size(); ++i) {
    same = haptics::sameFeaturePair(a[i], b[i]) && std::abs(a[i].distance_m - b[i].distance_m) < 1e-12;
  }
  if (!same) throw std::runtime_error("SNCH and Bullet returned different minima: the comparison is void");
}

void setSnchCounters(benchmark::State& state, const haptics::SnchQueryStats& st) {
  state.counters["tri_pairs"] = static_cast<double>(st.triangle_pairs_tested);
  state.counters["node_pairs"] = static_cast<double>(st.node_pairs_visited);
  state.counters["dist_pruned"] = static_cast<double>(st.pruned_by_distance);
  state.counters["cone_pruned"] = static_cast<double>(st.pruned_by_cone);
  state.counters["convex_pruned"] = static_cast<double>(st.pruned_by_convex_bound);
  state.counters["gjk_tests"] = static_cast<double>(st.convex_hull_tests);
}

void BM_GlobalSearch_Snch(benchmark::State& state) {
  Setup& s = setup();
  static const haptics::CollisionWorld world = haptics::makeCollisionWorld(s.scene, s.model);
  haptics::SnchGlobalSearch search;
  std::vector<haptics::LocalMinimum> out;
  for (auto _ : state) {
    search.search(world, s.fk, kCutoff_m, kPruneRadius_m, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["minima"] = static_cast<double>(out.size());
  state.counters["triangles"] = static_cast<double>(s.scene.numTriangles());
  setSnchCounters(state, search.lastStats());
}

// The Bullet search on `world`, timed after checking that it returns SNCH's minima.
void runBulletSearch(benchmark::State& state, const Setup& s, const haptics::CollisionWorld& world) {
  haptics::BulletGlobalSearch search(world);
  std::vector<haptics::LocalMinimum> out;
  std::vector<haptics::LocalMinimum> reference;
  haptics::SnchGlobalSearch snch;
  snch.search(world, s.fk, kCutoff_m, kPruneRadius_m, reference);
  search.search(world, s.fk, kCutoff_m, kPruneRadius_m, out);
  checkSameMinima(reference, out);
  for (auto _ : state) {
    search.search(world, s.fk, kCutoff_m, kPruneRadius_m, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["minima"] = static_cast<double>(out.size());
  state.counters["tri_pairs"] = static_cast<double>(search.lastTrianglePairs());
}

void BM_GlobalSearch_Bullet(benchmark::State& state) {
  Setup& s = setup();
  static const haptics::CollisionWorld world = haptics::makeCollisionWorld(s.scene, s.model);
  runBulletSearch(state, s, world);
}

void BM_GlobalSearch_Snch_Subdivided(benchmark::State& state) {
  Setup& s = setup();
  const haptics::Scene scene = subdivided(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, s.model);
  haptics::SnchGlobalSearch search;
  std::vector<haptics::LocalMinimum> out;
  for (auto _ : state) {
    search.search(world, s.fk, kCutoff_m, kPruneRadius_m, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["minima"] = static_cast<double>(out.size());
  state.counters["triangles"] = static_cast<double>(scene.numTriangles());
  setSnchCounters(state, search.lastStats());
}

void BM_GlobalSearch_Bullet_Subdivided(benchmark::State& state) {
  Setup& s = setup();
  const haptics::Scene scene = subdivided(static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
  const haptics::CollisionWorld world = haptics::makeCollisionWorld(scene, s.model);
  runBulletSearch(state, s, world);
  state.counters["triangles"] = static_cast<double>(scene.numTriangles());
}

BENCHMARK(BM_GlobalSearch_Snch)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GlobalSearch_Bullet)->Unit(benchmark::kMillisecond);
// 16,611 triangles (after the double-sided collapse) x 4, 16, 64: 66,444, 265,776 and 1,063,104
// triangles (one, two, three levels everywhere).
BENCHMARK(BM_GlobalSearch_Snch_Subdivided)
    ->Args({1, 1})
    ->Args({2, 2})
    ->Args({3, 3})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);
BENCHMARK(BM_GlobalSearch_Bullet_Subdivided)
    ->Args({1, 1})
    ->Args({2, 2})
    ->Args({3, 3})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(2);

// The DRC truss subdivided four times: 1,123,072 triangles.
const haptics::TriMesh& millionTriangleMesh() {
  static const haptics::TriMesh mesh = haptics::subdivideMidpoint(
      haptics::importMesh(sourceFile("scenes/meshes/gazebo-drc/drc_practice_truss/truss.dae")), 4);
  return mesh;
}

void BM_Hierarchy_BuildTree_1M(benchmark::State& state) {
  const haptics::TriMesh& mesh = millionTriangleMesh();
  for (auto _ : state) {
    const haptics::SnchTree tree = haptics::buildSnchTree(mesh);
    benchmark::DoNotOptimize(tree.nodes.data());
  }
  state.counters["triangles"] = mesh.numTriangles();
}

void BM_Hierarchy_BuildTreeAndCones_1M(benchmark::State& state) {
  const haptics::TriMesh& mesh = millionTriangleMesh();
  for (auto _ : state) {
    const haptics::MeshHierarchy h = haptics::buildMeshHierarchy(mesh);
    benchmark::DoNotOptimize(h.tree.nodes.data());
  }
  state.counters["triangles"] = mesh.numTriangles();
}

void BM_Hierarchy_Load_1M(benchmark::State& state) {
  const haptics::TriMesh& mesh = millionTriangleMesh();
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "fullarm_bench_hierarchy.snch";
  haptics::saveMeshHierarchy(haptics::buildMeshHierarchy(mesh), mesh, file);
  for (auto _ : state) {
    const std::optional<haptics::MeshHierarchy> h = haptics::loadMeshHierarchy(mesh, file);
    if (!h) throw std::runtime_error("the saved hierarchy did not load");
    benchmark::DoNotOptimize(h->tree.nodes.data());
  }
  state.counters["file_MB"] = static_cast<double>(std::filesystem::file_size(file)) / 1e6;
  std::filesystem::remove(file);
}

void BM_Peer_FclBvhBuild_1M(benchmark::State& state) {
  const haptics::TriMesh& mesh = millionTriangleMesh();
  for (auto _ : state) {
    const auto model = haptics::test::fclModel(mesh);
    benchmark::DoNotOptimize(model.get());
  }
}

BENCHMARK(BM_Hierarchy_BuildTree_1M)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Hierarchy_BuildTreeAndCones_1M)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Hierarchy_Load_1M)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Peer_FclBvhBuild_1M)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
