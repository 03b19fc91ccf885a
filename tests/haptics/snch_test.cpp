// SNCH pair query against two independent oracles:
// - brute force over all triangle pairs with the same local-minimum definition (the hierarchy,
//   distance bound and cone pruning must lose nothing and add nothing);
// - FCL's mesh-mesh distance (OBBRSS BVH): the smallest SNCH minimum is the global distance.
#include "fullarm/haptics/snch.hpp"

#include <gtest/gtest.h>

#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <cstdint>
#include <limits>
#include <memory>

#include "fcl_mesh.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

using test::bruteForceMinima;
using test::fclModel;
using test::randomPose;
using test::randomSmallMesh;

constexpr double kCutoff_m = 0.05;

// Object and link at a random relative pose with their centres 0.1-0.45 m apart.
std::pair<Eigen::Isometry3d, Eigen::Isometry3d> randomPair(std::mt19937& rng) {
  Eigen::Isometry3d X_WO = randomPose(rng, 0.5);
  Eigen::Isometry3d X_WL = randomPose(rng, 0.0);
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Vector3d dir = Eigen::Vector3d(n(rng), n(rng), n(rng)).normalized();
  X_WL.translation() = X_WO.translation() + std::uniform_real_distribution<double>(0.1, 0.45)(rng) * dir;
  return {X_WL, X_WO};
}

TEST(SnchTest, FindsExactlyTheBruteForceLocalMinima) {
  std::mt19937 rng(2024);
  int cases_with_minima = 0;
  int total_minima = 0;
  int edge_or_vertex = 0;
  long pruned_by_cone = 0;
  SnchQueryScratch scratch;
  for (int trial = 0; trial < 600; ++trial) {
    const TriMesh link = randomSmallMesh(rng);
    const TriMesh obj = randomSmallMesh(rng);
    const SnchTree link_tree = buildSnchTree(link);
    const SnchTree obj_tree = buildSnchTree(obj);
    const auto [X_WL, X_WO] = randomPair(rng);
    std::vector<LocalMinimum> snch;
    SnchQueryStats stats;
    querySnchPair(link_tree, link, X_WL, obj_tree, obj, X_WO, kCutoff_m, scratch, snch, &stats);
    pruned_by_cone += stats.pruned_by_cone;
    const std::vector<LocalMinimum> brute = bruteForceMinima(link, X_WL, obj, X_WO, kCutoff_m);
    ASSERT_EQ(snch.size(), brute.size()) << "trial " << trial << " (" << link.source() << " vs " << obj.source() << ")";
    for (std::size_t i = 0; i < snch.size(); ++i) {
      EXPECT_TRUE(sameFeaturePair(snch[i], brute[i])) << "trial " << trial;
      EXPECT_NEAR(snch[i].distance_m, brute[i].distance_m, 1e-12);
      EXPECT_NEAR((snch[i].u_W - brute[i].u_W).norm(), 0.0, 1e-9);
      if (snch[i].feature_link.kind != FeatureKind::kFace || snch[i].feature_object.kind != FeatureKind::kFace) {
        ++edge_or_vertex;
      }
    }
    if (!snch.empty()) ++cases_with_minima;
    total_minima += static_cast<int>(snch.size());
  }
  // The sample must exercise the interesting cases, not only empty queries.
  EXPECT_GT(cases_with_minima, 150);
  EXPECT_GT(edge_or_vertex, 100);
  EXPECT_GT(pruned_by_cone, 0);
  RecordProperty("cases_with_minima", cases_with_minima);
  RecordProperty("total_minima", total_minima);
}

// The query caches the link nodes in the object frame per query, stamped with a query counter:
// a scratch reused across different link trees (stale entries of another tree at the same
// index) and across the wrap of the counter must still give exactly the brute-force minima.
TEST(SnchTest, ScratchReusedAcrossTreesAndCounterWrap) {
  std::mt19937 rng(77);
  SnchQueryScratch scratch;
  int compared = 0;
  for (int trial = 0; trial < 60; ++trial) {
    const TriMesh link = randomSmallMesh(rng);
    const TriMesh obj = randomSmallMesh(rng);
    const SnchTree link_tree = buildSnchTree(link);
    const SnchTree obj_tree = buildSnchTree(obj);
    const auto [X_WL, X_WO] = randomPair(rng);
    // Every third trial starts right below the wrap of the counter (the stamps of the previous
    // trial's tree are then max - 1 or max, and the wrap resets them).
    if (trial % 3 == 0) scratch.query = std::numeric_limits<std::uint32_t>::max() - 1;
    for (int repeat = 0; repeat < 3; ++repeat) {
      std::vector<LocalMinimum> snch;
      querySnchPair(link_tree, link, X_WL, obj_tree, obj, X_WO, kCutoff_m, scratch, snch);
      const std::vector<LocalMinimum> brute = bruteForceMinima(link, X_WL, obj, X_WO, kCutoff_m);
      ASSERT_EQ(snch.size(), brute.size()) << "trial " << trial << " repeat " << repeat;
      for (std::size_t i = 0; i < snch.size(); ++i) {
        EXPECT_TRUE(sameFeaturePair(snch[i], brute[i])) << "trial " << trial;
        EXPECT_NEAR(snch[i].distance_m, brute[i].distance_m, 1e-12);
      }
      compared += static_cast<int>(snch.size());
    }
  }
  EXPECT_GT(compared, 20);  // the sample holds minima, not only empty queries
}

double fclDistance(const std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>& a, const Eigen::Isometry3d& X_WA,
                   const std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>& b, const Eigen::Isometry3d& X_WB,
                   fcl::Vector3d* p_a = nullptr, fcl::Vector3d* p_b = nullptr) {
  fcl::CollisionObjectd oa(a, X_WA);
  fcl::CollisionObjectd ob(b, X_WB);
  fcl::DistanceRequestd req;
  req.enable_nearest_points = true;
  req.rel_err = 0.0;
  req.abs_err = 0.0;
  fcl::DistanceResultd res;
  fcl::distance(&oa, &ob, req, res);
  if (p_a != nullptr) *p_a = res.nearest_points[0];  // world frame (FCL >= 0.6)
  if (p_b != nullptr) *p_b = res.nearest_points[1];
  return res.min_distance;
}

TEST(SnchTest, SmallestMinimumEqualsFclDistance) {
  std::mt19937 rng(99);
  SnchQueryScratch scratch;
  int compared = 0;
  for (int trial = 0; trial < 1300; ++trial) {
    const TriMesh link = randomSmallMesh(rng);
    const TriMesh obj = randomSmallMesh(rng);
    auto [X_WL, X_WO] = randomPair(rng);
    const auto link_fcl = fclModel(link);
    const auto obj_fcl = fclModel(obj);
    // Slide the link along the closest-point direction so the gap lands near a random target
    // within the cutoff; the distance compared is FCL's at the final pose.
    fcl::Vector3d p_link;
    fcl::Vector3d p_obj;
    const double d0 = fclDistance(link_fcl, X_WL, obj_fcl, X_WO, &p_link, &p_obj);
    if (d0 > 0.0) {
      const double target = std::uniform_real_distribution<double>(0.0005, 0.045)(rng);
      X_WL.translation() -= (d0 - target) * (p_link - p_obj).normalized();
    }
    const double d_fcl = fclDistance(link_fcl, X_WL, obj_fcl, X_WO);
    if (!(d_fcl > 0.0 && d_fcl < kCutoff_m)) continue;
    std::vector<LocalMinimum> snch;
    querySnchPair(buildSnchTree(link), link, X_WL, buildSnchTree(obj), obj, X_WO, kCutoff_m, scratch, snch);
    ASSERT_FALSE(snch.empty()) << "trial " << trial;
    const double d_min = std::min_element(snch.begin(), snch.end(), [](const auto& x, const auto& y) {
                           return x.distance_m < y.distance_m;
                         })->distance_m;
    EXPECT_NEAR(d_min, d_fcl, 1e-9) << "trial " << trial;
    ++compared;
  }
  EXPECT_GE(compared, 1000);
}

TEST(SnchTest, TreeBoundsEveryTriangleAndEveryOneRingNormal) {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const TriMesh m = randomSmallMesh(rng);
    const SnchTree tree = buildSnchTree(m);
    ASSERT_EQ(tree.nodes.size(), static_cast<std::size_t>(2 * m.numTriangles() - 1));
    // Walk every root-to-leaf path: ancestors contain the leaf triangle and its cone normals.
    std::vector<std::vector<int>> path{{0}};
    std::vector<std::pair<int, std::vector<int>>> stack{{0, {}}};
    while (!stack.empty()) {
      auto [id, anc] = stack.back();
      stack.pop_back();
      anc.push_back(id);
      const SnchNode& n = tree.nodes[static_cast<std::size_t>(id)];
      if (!n.isLeaf()) {
        stack.push_back({n.left, anc});
        stack.push_back({n.right, anc});
        continue;
      }
      const auto& tri = m.triangle(n.triangle);
      for (int a : anc) {
        const SnchNode& A = tree.nodes[static_cast<std::size_t>(a)];
        for (int k = 0; k < 3; ++k) {
          EXPECT_LE((m.vertex(tri[k]) - A.centre_m).norm(), A.radius_m);
          for (int s : m.vertexTriangles(tri[k])) {
            const double angle = std::acos(std::clamp(A.cone_axis.dot(m.faceNormal(s)), -1.0, 1.0));
            EXPECT_LE(angle, A.cone_half_angle_rad + 1e-9);
          }
        }
      }
    }
  }
}

}  // namespace
}  // namespace fullarm::haptics
