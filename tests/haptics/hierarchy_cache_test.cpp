// Saved hierarchies: a saved and reloaded hierarchy equals the built one field for field, and
// queries on it return the same minima; a file saved for another mesh or another build version,
// truncated or corrupted bytes are rejected (never a crash) and the cache rebuilds them; a scene's
// `hierarchy_cache` folder is filled on the first load and read on the second.
#include "fullarm/haptics/hierarchy_cache.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <random>

#include "arm_test_util.hpp"
#include "fullarm/haptics/mesh_import.hpp"
#include "fullarm/haptics/mesh_subdivision.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/scene.hpp"
#include "haptics_test_util.hpp"
#include "scratch_dir.hpp"

namespace fullarm::haptics {
namespace {

TriMesh wheel() {
  return importMesh(arm::test::sourcePath("scenes/meshes/gazebo-drc/drc_practice_wheel_valve/valve_wheel.dae"));
}

std::string readBytes(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void writeBytes(const std::filesystem::path& file, const std::string& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

void expectSameHierarchy(const MeshHierarchy& a, const MeshHierarchy& b) {
  ASSERT_EQ(a.tree.nodes.size(), b.tree.nodes.size());
  for (std::size_t i = 0; i < a.tree.nodes.size(); ++i) {
    const SnchNode& x = a.tree.nodes[i];
    const SnchNode& y = b.tree.nodes[i];
    ASSERT_TRUE(x.centre_m == y.centre_m && x.radius_m == y.radius_m && x.box_half_m == y.box_half_m &&
                x.left == y.left && x.right == y.right && x.cone_axis == y.cone_axis &&
                x.cone_half_angle_rad == y.cone_half_angle_rad && x.cone_cos == y.cone_cos &&
                x.cone_sin == y.cone_sin && x.triangle == y.triangle && x.cone_two_sided == y.cone_two_sided)
        << "node " << i;
  }
  EXPECT_EQ(a.tree.leaf_of_triangle, b.tree.leaf_of_triangle);
  EXPECT_EQ(a.tree.convex, b.tree.convex);
  EXPECT_EQ(a.tree.vertex_graph.offset, b.tree.vertex_graph.offset);
  EXPECT_EQ(a.tree.vertex_graph.neighbours, b.tree.vertex_graph.neighbours);
  EXPECT_EQ(a.tree.support_table.start_vertex, b.tree.support_table.start_vertex);
  EXPECT_EQ(a.tree.bracket.a_m, b.tree.bracket.a_m);
  EXPECT_EQ(a.tree.bracket.inner_radius_m, b.tree.bracket.inner_radius_m);
  EXPECT_EQ(a.cones.vertex, b.cones.vertex);
  EXPECT_EQ(a.cones.edge, b.cones.edge);
}

TEST(HierarchyCacheTest, SavedHierarchyReloadsFieldForFieldAndQueriesAlike) {
  const std::filesystem::path dir = fullarm::test::scratchDir("hierarchy_roundtrip");
  for (const TriMesh& mesh : {wheel(), makeCapsule({0, 0, 0}, {0, 0, 0.2}, 0.05, 12, 3)}) {
    const MeshHierarchy built = buildMeshHierarchy(mesh);
    const std::filesystem::path file = dir / "h.snch";
    saveMeshHierarchy(built, mesh, file);
    std::string why;
    const std::optional<MeshHierarchy> loaded = loadMeshHierarchy(mesh, file, &why);
    ASSERT_TRUE(loaded.has_value()) << why;
    expectSameHierarchy(built, *loaded);
    // Capsule queries at random poses near the mesh: the same minima with either tree.
    std::mt19937 rng(9);
    SnchQueryScratch scratch;
    const Capsule capsule{{0, 0, -0.1}, {0, 0, 0.1}, 0.03};
    int minima = 0;
    for (int i = 0; i < 200; ++i) {
      const Eigen::Isometry3d X_WL = test::randomPose(rng, 0.25);
      std::vector<LocalMinimum> a;
      std::vector<LocalMinimum> b;
      querySnchCapsule(capsule, X_WL, built.tree, mesh, Eigen::Isometry3d::Identity(), 0.05, scratch, a);
      querySnchCapsule(capsule, X_WL, loaded->tree, mesh, Eigen::Isometry3d::Identity(), 0.05, scratch, b);
      ASSERT_EQ(a.size(), b.size());
      for (std::size_t k = 0; k < a.size(); ++k) {
        EXPECT_TRUE(sameFeaturePair(a[k], b[k]));
        EXPECT_EQ(a[k].distance_m, b[k].distance_m);
      }
      minima += static_cast<int>(a.size());
    }
    EXPECT_GT(minima, 20);
  }
}

TEST(HierarchyCacheTest, StaleOrDamagedFilesAreRejectedAndRebuilt) {
  const std::filesystem::path dir = fullarm::test::scratchDir("hierarchy_stale");
  const TriMesh mesh = subdivideMidpoint(makeBox({0.3, 0.2, 0.1}, 0.05), 1);
  HierarchyCacheOutcome outcome{};
  const MeshHierarchy first = hierarchyFromCache(mesh, dir, &outcome);
  EXPECT_EQ(outcome, HierarchyCacheOutcome::kBuiltAndSaved);
  const std::filesystem::path file = hierarchyCacheFile(mesh, dir);
  ASSERT_TRUE(std::filesystem::exists(file));
  EXPECT_EQ(file.filename().string().size(), 16U + 5U);  // the content hash in hex, ".snch"
  const MeshHierarchy second = hierarchyFromCache(mesh, dir, &outcome);
  EXPECT_EQ(outcome, HierarchyCacheOutcome::kLoaded);
  expectSameHierarchy(first, second);
  const std::string good = readBytes(file);

  // Another mesh: one vertex moved by 1 um. Its hash differs (another file name), and the old
  // file read for it is stale.
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(mesh.vertex(i));
  for (int i = 0; i < mesh.numTriangles(); ++i) t.push_back(mesh.triangle(i));
  v[7].x() += 1e-6;
  const TriMesh moved = TriMesh::build("moved", v, t);
  EXPECT_NE(meshContentHash(moved), meshContentHash(mesh));
  std::string why;
  EXPECT_FALSE(loadMeshHierarchy(moved, file, &why).has_value());
  EXPECT_NE(why.find("another mesh"), std::string::npos) << why;
  // ... and put under the moved mesh's name, it is rebuilt and replaced.
  const std::filesystem::path moved_file = hierarchyCacheFile(moved, dir);
  writeBytes(moved_file, good);
  const MeshHierarchy rebuilt = hierarchyFromCache(moved, dir, &outcome);
  EXPECT_EQ(outcome, HierarchyCacheOutcome::kRebuiltStale);
  expectSameHierarchy(rebuilt, buildMeshHierarchy(moved));
  EXPECT_TRUE(loadMeshHierarchy(moved, moved_file).has_value());

  // Another build version (the header's second word after the magic).
  std::string other_version = good;
  other_version[8 + 4] = static_cast<char>(other_version[8 + 4] + 1);
  writeBytes(file, other_version);
  EXPECT_FALSE(loadMeshHierarchy(mesh, file, &why).has_value());
  EXPECT_NE(why.find("stale: built by version"), std::string::npos) << why;
  (void)hierarchyFromCache(mesh, dir, &outcome);
  EXPECT_EQ(outcome, HierarchyCacheOutcome::kRebuiltStale);
  EXPECT_EQ(readBytes(file), good);

  // Truncations and flipped bytes: rejected, never a crash, and the cache rebuilds.
  std::mt19937 rng(3);
  int rejected = 0;
  for (int trial = 0; trial < 60; ++trial) {
    std::string bad = good;
    if (trial % 2 == 0) {
      bad.resize(std::uniform_int_distribution<std::size_t>(0, good.size() - 1)(rng));
    } else {
      const std::size_t at = std::uniform_int_distribution<std::size_t>(0, good.size() - 1)(rng);
      bad[at] = static_cast<char>(bad[at] ^ (1 << (trial % 8)));
    }
    writeBytes(file, bad);
    rejected += loadMeshHierarchy(mesh, file).has_value() ? 0 : 1;
  }
  EXPECT_EQ(rejected, 60);
  (void)hierarchyFromCache(mesh, dir, &outcome);
  EXPECT_EQ(outcome, HierarchyCacheOutcome::kRebuiltStale);
  EXPECT_EQ(readBytes(file), good);
  EXPECT_FALSE(loadMeshHierarchy(mesh, dir / "missing.snch", &why).has_value());
  EXPECT_NE(why.find("no such file"), std::string::npos);
}

TEST(HierarchyCacheTest, SceneCacheFolderIsFilledThenRead) {
  const std::filesystem::path dir = fullarm::test::scratchDir("hierarchy_scene");
  const std::string yaml =
      "schema_version: 1\n"
      "name: cached\n"
      "hierarchy_cache: cache\n"
      "arm: {shoulder_m: [0.0, 0.0, 1.4]}\n"
      "objects:\n"
      "  - {name: a, pose: {translation_m: [0.3, 0.3, 1.2]}, shape: {type: box, size_m: [0.2, 0.2, 0.2], max_edge_m: "
      "0.05}}\n"
      "  - {name: b, pose: {translation_m: [0.3, -0.3, 1.2]}, shape: {type: rectangular_frame, outer_width_m: 0.3, "
      "outer_height_m: 0.3, bar_width_m: 0.05, depth_m: 0.05, max_edge_m: 0.05}}\n";
  const Scene scene = parseScene(yaml, dir / "cached.yaml");
  EXPECT_EQ(scene.hierarchy_cache_dir, dir / "cache");
  const arm::ArmModel& model = arm::test::defaultModel();
  const CollisionWorld first = makeCollisionWorld(scene, model);
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir / "cache"))
    files += entry.path().extension() == ".snch" ? 1 : 0;
  EXPECT_EQ(files, 2);
  const CollisionWorld second = makeCollisionWorld(scene, model);
  for (int o = 0; o < 2; ++o) {
    expectSameHierarchy({first.object(o).tree, first.object(o).cones}, {second.object(o).tree, second.object(o).cones});
  }
  // A bad key value names the key.
  try {
    (void)parseScene(
        "schema_version: 1\nname: x\nhierarchy_cache: ''\narm: {shoulder_m: [0, 0, 1]}\nobjects:\n"
        "  - {name: a, pose: {translation_m: [0, 0, 0]}, shape: {type: box, size_m: [0.1, 0.1, 0.1], max_edge_m: "
        "0.1}}\n",
        dir / "bad.yaml");
    ADD_FAILURE() << "an empty hierarchy_cache must be an error";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("hierarchy_cache"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace fullarm::haptics
