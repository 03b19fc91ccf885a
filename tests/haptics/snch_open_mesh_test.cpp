// SNCH pair query against brute force over all triangle pairs on the meshes real CAD exports
// give: open surfaces (boundary edges), double-sided surfaces (every triangle also present with
// the opposite winding, as in the DRC valve wall and wheel), and both, on the random primitives
// and on folded sheets (acute and obtuse folds). The hierarchy's box bounds and cone tests must
// lose no local minimum and add none.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "fullarm/haptics/snch.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

using test::bruteForceMinima;
using test::randomPose;
using test::randomSmallMesh;

constexpr double kCutoff_m = 0.05;

enum class Variant { kClosed, kOpen, kDoubleSided, kOpenDoubleSided };

// An open sheet of two 0.1 x 0.1 m panels folded along a shared edge by a random angle between
// the panels of 15-165 degrees (acute folds: the outside normal wedge spans more than 90
// degrees), gridded so it has interior vertices.
TriMesh foldedSheet(std::mt19937& rng) {
  const double fold = std::uniform_real_distribution<double>(0.26, 2.88)(rng);
  test::FoldGrid g = test::foldGrid(fold, 5, /*face_outside=*/true);
  // The fold line (j = 0) is shared: weld the duplicated vertices.
  return TriMesh::build("folded sheet", std::move(g.vertices), std::move(g.triangles), 1e-9);
}

// `mesh` with a random 10-40 % of its triangles removed (kOpen), with every triangle repeated
// in the opposite winding (kDoubleSided), or both.
TriMesh variantOf(const TriMesh& mesh, Variant variant, std::mt19937& rng) {
  if (variant == Variant::kClosed) return mesh;
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(mesh.vertex(i));
  std::vector<Eigen::Vector3i> t;
  const double drop = std::uniform_real_distribution<double>(0.1, 0.4)(rng);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < mesh.numTriangles(); ++i) {
    if ((variant == Variant::kOpen || variant == Variant::kOpenDoubleSided) && u(rng) < drop) continue;
    t.push_back(mesh.triangle(i));
  }
  if (t.empty()) t.push_back(mesh.triangle(0));
  if (variant == Variant::kDoubleSided || variant == Variant::kOpenDoubleSided) {
    const std::size_t n = t.size();
    for (std::size_t i = 0; i < n; ++i) t.emplace_back(t[i][0], t[i][2], t[i][1]);
  }
  return TriMesh::build(mesh.source() + " (variant)", std::move(v), std::move(t));
}

// The link placed so that one of its vertices lies 0.5-45 mm from a random vertex of the object
// (for an open mesh preferably a rim vertex, approached from any direction), random turn.
std::pair<Eigen::Isometry3d, Eigen::Isometry3d> nearVertexPair(const TriMesh& link, const TriMesh& obj,
                                                               std::mt19937& rng) {
  const Eigen::Isometry3d X_WO = randomPose(rng, 0.5);
  Eigen::Isometry3d X_OL = randomPose(rng, 0.0);
  std::vector<int> rim;
  for (int e = 0; e < obj.numEdges(); ++e) {
    if (obj.edgeTriangles(e).size() == 1) rim.push_back(obj.edgeVertices(e)[0]);
  }
  int v = std::uniform_int_distribution<int>(0, obj.numVertices() - 1)(rng);
  if (!rim.empty() && std::uniform_real_distribution<double>(0.0, 1.0)(rng) < 0.7) {
    v = rim[std::uniform_int_distribution<std::size_t>(0, rim.size() - 1)(rng)];
  }
  const int w = std::uniform_int_distribution<int>(0, link.numVertices() - 1)(rng);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  const double gap = std::uniform_real_distribution<double>(0.0005, 0.045)(rng);
  X_OL.translation() = obj.vertex(v) + gap * dir - X_OL.linear() * link.vertex(w);
  return {X_WO * X_OL, X_WO};
}

TEST(SnchOpenMeshTest, FindsExactlyTheBruteForceLocalMinimaOnOpenAndDoubleSidedMeshes) {
  std::mt19937 rng(77);
  SnchQueryScratch scratch;
  int cases_with_minima = 0;
  int on_rim = 0;  // minima with the object feature on a boundary edge or vertex
  long pruned_by_cone = 0;
  long pruned_by_distance = 0;
  std::uniform_int_distribution<int> pick(0, 3);
  for (int trial = 0; trial < 600; ++trial) {
    const TriMesh link = variantOf(randomSmallMesh(rng), static_cast<Variant>(pick(rng)), rng);
    const bool fold = std::uniform_real_distribution<double>(0.0, 1.0)(rng) < 0.3;
    const TriMesh obj = variantOf(fold ? foldedSheet(rng) : randomSmallMesh(rng), static_cast<Variant>(pick(rng)), rng);
    const auto [X_WL, X_WO] = nearVertexPair(link, obj, rng);
    std::vector<LocalMinimum> snch;
    SnchQueryStats stats;
    querySnchPair(buildSnchTree(link), link, X_WL, buildSnchTree(obj), obj, X_WO, kCutoff_m, scratch, snch, &stats);
    pruned_by_cone += stats.pruned_by_cone;
    pruned_by_distance += stats.pruned_by_distance;
    const std::vector<LocalMinimum> brute = bruteForceMinima(link, X_WL, obj, X_WO, kCutoff_m);
    ASSERT_EQ(snch.size(), brute.size()) << "trial " << trial << " (" << link.source() << " vs " << obj.source() << ")";
    for (std::size_t i = 0; i < snch.size(); ++i) {
      EXPECT_TRUE(sameFeaturePair(snch[i], brute[i])) << "trial " << trial;
      EXPECT_NEAR(snch[i].distance_m, brute[i].distance_m, 1e-12);
      EXPECT_NEAR((snch[i].u_W - brute[i].u_W).norm(), 0.0, 1e-9);
      const Feature& f = snch[i].feature_object;
      if (f.kind == FeatureKind::kEdge && obj.edgeTriangles(f.index).size() == 1) ++on_rim;
    }
    if (!snch.empty()) ++cases_with_minima;
  }
  // The sample must exercise rims and both pruning tests, not only empty queries.
  EXPECT_GT(cases_with_minima, 300);
  EXPECT_GT(on_rim, 50);
  EXPECT_GT(pruned_by_cone, 0);
  EXPECT_GT(pruned_by_distance, 0);
  RecordProperty("cases_with_minima", cases_with_minima);
  RecordProperty("minima_on_rim_edges", on_rim);
}

}  // namespace
}  // namespace fullarm::haptics
