// The smallest SNCH minimum against independent distances on the DRC meshes and the tube frames
// of scenes/valve_wall.yaml, at seeded random poses whose distance lies in (0, L):
// - the exact capsule links (the arm model's capsules) against a long-double segment-triangle
//   oracle minus the radius (1e-9 m) and against FCL's capsule-mesh distance (1e-6 m), 1,280
//   poses over the valve wall, the wheel valve, the opening's 30 mm tube frame and a 20 mm tube
//   frame;
// - the links as faceted 16 x 4 meshes (the mesh-link path) against FCL's mesh-mesh distance
//   (1e-9 m), against the valve wall and the wheel valve.
//
// The DRC meshes are two-sided: every triangle appears twice, once per winding (the valve wall
// 1640 of its 3280 triangles, the wheel 5496 of 10992), so pseudo-normals of shared features
// cancel and cannot give an outward direction. Pose generation therefore uses face normals only:
// a random point x on a random triangle of the object (area-weighted), a random direction w in
// the hemisphere of that triangle's face normal n (w . n > 0, either side of the sheet at
// random), a random link orientation, and the link translated so that its extreme point
// against w (its support point in direction -w) lands at x + s w with s uniform in (0, L).
// The link then lies in the half-space {y : w . (y - x) >= s}, so the mesh distance is at most
// s < L; other parts of the object may come closer or intersect, which is why only poses with
// an FCL distance in (0, L) are compared.
#include <gtest/gtest.h>

#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/narrowphase/distance.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "arm_test_util.hpp"
#include "fcl_mesh.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/scene.hpp"
#include "fullarm/haptics/snch.hpp"
#include "haptics_test_util.hpp"
#include "segment_oracle.hpp"

namespace fullarm::haptics {
namespace {

using test::fclModel;

constexpr double kCutoff_m = 0.03;  // L of config/haptics.yaml
constexpr double kTolerance_m = 1e-9;
constexpr double kFclTolerance_m = 1e-6;  // FCL's GJK (libccd) asked for 1e-9, see fclCapsuleDistance
constexpr int kAcceptedPerPair = 100;
constexpr int kMaxTriesPerPair = 2000;

double fclDistance(const std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>& a, const Eigen::Isometry3d& X_WA,
                   const std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>& b, const Eigen::Isometry3d& X_WB) {
  fcl::CollisionObjectd oa(a, X_WA);
  fcl::CollisionObjectd ob(b, X_WB);
  fcl::DistanceRequestd req;
  req.enable_nearest_points = false;
  req.rel_err = 0.0;
  req.abs_err = 0.0;
  fcl::DistanceResultd res;
  fcl::distance(&oa, &ob, req, res);
  return res.min_distance;
}

// Area-weighted random triangle of `mesh` and a uniform point on it (object frame).
struct SurfaceSample {
  int triangle = -1;
  Eigen::Vector3d point;
};

class SurfaceSampler {
 public:
  explicit SurfaceSampler(const TriMesh& mesh) : mesh_(mesh) {
    double sum = 0.0;
    for (int t = 0; t < mesh.numTriangles(); ++t) {
      const auto& tri = mesh.triangle(t);
      sum += 0.5 * (mesh.vertex(tri[1]) - mesh.vertex(tri[0])).cross(mesh.vertex(tri[2]) - mesh.vertex(tri[0])).norm();
      cumulative_.push_back(sum);
    }
  }
  SurfaceSample operator()(std::mt19937& rng) const {
    const double r = std::uniform_real_distribution<double>(0.0, cumulative_.back())(rng);
    const int t = static_cast<int>(std::upper_bound(cumulative_.begin(), cumulative_.end(), r) - cumulative_.begin());
    const int tri_index = std::min(t, mesh_.numTriangles() - 1);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    double a = u(rng);
    double b = u(rng);
    if (a + b > 1.0) {
      a = 1.0 - a;
      b = 1.0 - b;
    }
    const auto& tri = mesh_.triangle(tri_index);
    const Eigen::Vector3d& v0 = mesh_.vertex(tri[0]);
    return {tri_index, v0 + a * (mesh_.vertex(tri[1]) - v0) + b * (mesh_.vertex(tri[2]) - v0)};
  }

 private:
  const TriMesh& mesh_;
  std::vector<double> cumulative_;
};

Eigen::Vector3d randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d v(n(rng), n(rng), n(rng));
  while (v.norm() < 1e-6) v = Eigen::Vector3d(n(rng), n(rng), n(rng));
  return v.normalized();
}

// The link pose (world) that puts the link's support point against w_W at x_W + gap_m w_W.
Eigen::Isometry3d placeLink(const TriMesh& link_mesh, const Eigen::Matrix3d& R_WL, const Eigen::Vector3d& x_W,
                            const Eigen::Vector3d& w_W, double gap_m) {
  const Eigen::Vector3d w_L = R_WL.transpose() * w_W;
  int support = 0;
  for (int v = 1; v < link_mesh.numVertices(); ++v) {
    if (link_mesh.vertex(v).dot(w_L) < link_mesh.vertex(support).dot(w_L)) support = v;
  }
  Eigen::Isometry3d X_WL = Eigen::Isometry3d::Identity();
  X_WL.linear() = R_WL;
  X_WL.translation() = x_W + gap_m * w_W - R_WL * link_mesh.vertex(support);
  return X_WL;
}

struct PairSummary {
  int accepted = 0;
  int tried = 0;
  double max_error_m = 0.0;
};

// Compares SNCH with FCL for every arm link mesh against the scene object `object_name`,
// kAcceptedPerPair poses per link; returns the number of poses compared.
int compareEveryLinkWithFcl(const std::string& object_name, std::uint32_t seed) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  CollisionWorld world = makeCollisionWorld(scene, model);
  test::facetCapsuleLinks(world, 16, 4);
  std::vector<int> links;
  for (int l = 0; l < world.numLinks(); ++l) {
    if (world.hasLinkMesh(l)) links.push_back(l);
  }
  EXPECT_GE(links.size(), 3U);
  const int o = world.objectIndex(object_name);
  EXPECT_GE(o, 0) << object_name;
  if (o < 0) return 0;
  const CollisionObject& obj = world.object(o);
  const auto obj_fcl = fclModel(obj.mesh);
  const SurfaceSampler sample(obj.mesh);
  std::cout << obj.name << ": " << obj.mesh.numTriangles() << " triangles, " << obj.mesh.boundaryEdgeCount()
            << " boundary edges, " << obj.mesh.nonManifoldEdgeCount() << " non-manifold edges\n";

  std::mt19937 rng(seed);
  SnchQueryScratch scratch;
  int total = 0;
  double max_error = 0.0;
  std::array<int, 3> object_feature{};  // closest object feature of the smallest minimum: face, edge, vertex
  for (const int l : links) {
    const TriMesh& link_mesh = world.linkMesh(l);
    const auto link_fcl = fclModel(link_mesh);
    PairSummary pair;
    while (pair.accepted < kAcceptedPerPair && pair.tried < kMaxTriesPerPair) {
      ++pair.tried;
      const SurfaceSample s = sample(rng);
      const Eigen::Vector3d& n = obj.mesh.faceNormal(s.triangle);
      Eigen::Vector3d w = randomUnit(rng);
      if (w.dot(n) < 0.0) w = -w;
      const Eigen::Vector3d x_W = obj.X_WO * s.point;
      const Eigen::Vector3d w_W = obj.X_WO.linear() * w;
      std::normal_distribution<double> g(0.0, 1.0);
      const Eigen::Matrix3d R = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
      const double gap = std::uniform_real_distribution<double>(0.0, kCutoff_m)(rng);
      const Eigen::Isometry3d X_WL = placeLink(link_mesh, R, x_W, w_W, gap);
      const double d_fcl = fclDistance(link_fcl, X_WL, obj_fcl, obj.X_WO);
      if (!(d_fcl > 0.0 && d_fcl < kCutoff_m)) continue;  // intersecting elsewhere
      std::vector<LocalMinimum> snch;
      querySnchPair(world.linkTree(l), link_mesh, X_WL, obj.tree, obj.mesh, obj.X_WO, kCutoff_m, scratch, snch);
      ++pair.accepted;
      EXPECT_FALSE(snch.empty()) << obj.name << " vs link " << l << ", pose " << pair.tried << ": FCL " << d_fcl;
      if (snch.empty()) continue;
      const LocalMinimum& m = *std::min_element(
          snch.begin(), snch.end(), [](const auto& a, const auto& b) { return a.distance_m < b.distance_m; });
      EXPECT_NEAR(m.distance_m, d_fcl, kTolerance_m) << obj.name << " vs link " << l << ", pose " << pair.tried;
      // The reported endpoints (local frames) are that far apart in the world.
      EXPECT_NEAR((obj.X_WO * m.p_O - X_WL * m.p_L).norm(), m.distance_m, 1e-12);
      pair.max_error_m = std::max(pair.max_error_m, std::abs(m.distance_m - d_fcl));
      ++object_feature[static_cast<std::size_t>(m.feature_object.kind)];
    }
    std::cout << "  link " << l << " (" << link_mesh.numTriangles() << " triangles): " << pair.accepted << " of "
              << pair.tried << " poses compared, max |SNCH - FCL| = " << pair.max_error_m << " m\n";
    EXPECT_EQ(pair.accepted, kAcceptedPerPair) << obj.name << " vs link " << l;
    total += pair.accepted;
    max_error = std::max(max_error, pair.max_error_m);
  }
  std::cout << obj.name << ": " << total << " poses, max |SNCH - FCL| = " << max_error
            << " m; closest object feature: face " << object_feature[0] << ", edge " << object_feature[1] << ", vertex "
            << object_feature[2] << "\n";
  // Edge and vertex minima on the object must be among the compared cases.
  EXPECT_GT(object_feature[1] + object_feature[2], total / 20);
  return total;
}

// Every arm link as its faceted mesh against the DRC valve wall (the 1.22 x 2.44 m plywood sheet)
// and against the DRC wheel valve: 5 links x 100 poses each; together the two tests compare 1000
// poses.
TEST(FclDrcTest, SmallestSnchMinimumEqualsFclDistanceForFacetedLinksAgainstTheValveWall) {
  const int poses = compareEveryLinkWithFcl("valve_wall", 20261121);
  RecordProperty("poses", poses);
  EXPECT_GE(poses, 500);
}

TEST(FclDrcTest, SmallestSnchMinimumEqualsFclDistanceForFacetedLinksAgainstTheWheelValve) {
  const int poses = compareEveryLinkWithFcl("wheel_valve", 20261122);
  RecordProperty("poses", poses);
  EXPECT_GE(poses, 500);
}

// ---------------------------------------------------------------------------------------------
// Exact capsule links.

using test::segmentTriangleOracle;
using test::toLong;

// Distance from a capsule (segment a, b and radius, object frame) to a whole mesh by the oracle:
// triangles in order of a sphere lower bound, stopping once the bound passes the best distance.
double capsuleMeshOracle(const Eigen::Vector3d& a, const Eigen::Vector3d& b, double radius, const TriMesh& mesh) {
  std::vector<std::pair<double, int>> order;
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    const auto& tri = mesh.triangle(t);
    const Eigen::Vector3d centre = (mesh.vertex(tri[0]) + mesh.vertex(tri[1]) + mesh.vertex(tri[2])) / 3.0;
    double r = 0.0;
    for (int k = 0; k < 3; ++k) r = std::max(r, (mesh.vertex(tri[k]) - centre).norm());
    const double s = closestSegmentParameter(a, b, centre);
    order.emplace_back((centre - (a + s * (b - a))).norm() - r, t);
  }
  std::sort(order.begin(), order.end());
  long double best = std::numeric_limits<long double>::infinity();
  for (const auto& [bound, t] : order) {
    if (bound > static_cast<double>(best) + 1e-9) break;
    const auto& tri = mesh.triangle(t);
    best = std::min(best, segmentTriangleOracle(toLong(a), toLong(b), toLong(mesh.vertex(tri[0])),
                                                toLong(mesh.vertex(tri[1])), toLong(mesh.vertex(tri[2]))));
  }
  return static_cast<double>(std::max(0.0L, best - static_cast<long double>(radius)));
}

// FCL's distance between a capsule (link frame, placed at X_WL) and a mesh model at X_WO.
double fclCapsuleDistance(const Capsule& c, const Eigen::Isometry3d& X_WL,
                          const std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>& mesh, const Eigen::Isometry3d& X_WO) {
  const test::FclCapsule shape = test::fclCapsule(c);
  fcl::CollisionObjectd oc(shape.shape, X_WL * shape.X_LC);
  fcl::CollisionObjectd om(mesh, X_WO);
  fcl::DistanceRequestd req;
  req.enable_nearest_points = false;
  req.rel_err = 0.0;
  req.abs_err = 0.0;
  // GJK's stopping threshold: at FCL's default (1e-6) its capsule-mesh distances came out up to
  // 1.25e-5 m long on these poses; at 1e-9 they agree with the oracle to 2.1e-7 m.
  req.distance_tolerance = 1e-9;
  fcl::DistanceResultd res;
  fcl::distance(&oc, &om, req, res);
  return res.min_distance;
}

struct CapsuleSummary {
  int poses = 0;
  double max_oracle_error_m = 0.0;
  double max_fcl_error_m = 0.0;
  std::array<int, 3> object_feature{};  // face, edge, vertex of the smallest minimum
};

// `poses` seeded random capsule poses of the world's capsule links (in turn) against `obj` with a
// distance in (0, L): SNCH's smallest minimum against the oracle and FCL.
CapsuleSummary compareCapsulesWithOracles(const CollisionWorld& world, const CollisionObject& obj, int poses,
                                          std::uint32_t seed) {
  std::vector<int> links;
  for (int l = 0; l < world.numLinks(); ++l) {
    if (world.linkShape(l) == LinkShape::kCapsule) links.push_back(l);
  }
  EXPECT_GE(links.size(), 3U);
  const auto obj_fcl = fclModel(obj.mesh);
  const SurfaceSampler sample(obj.mesh);
  std::mt19937 rng(seed);
  SnchQueryScratch scratch;
  CapsuleSummary sum;
  int tried = 0;
  while (sum.poses < poses && tried < 20 * poses) {
    ++tried;
    const int l = links[static_cast<std::size_t>(tried) % links.size()];
    const Capsule& c = world.linkCapsule(l);
    const SurfaceSample s = sample(rng);
    Eigen::Vector3d w = randomUnit(rng);
    if (w.dot(obj.mesh.faceNormal(s.triangle)) < 0.0) w = -w;
    const Eigen::Vector3d x_W = obj.X_WO * s.point;
    const Eigen::Vector3d w_W = obj.X_WO.linear() * w;
    std::normal_distribution<double> g(0.0, 1.0);
    const Eigen::Matrix3d R = Eigen::Quaterniond(g(rng), g(rng), g(rng), g(rng)).normalized().toRotationMatrix();
    const double gap = std::uniform_real_distribution<double>(0.0, kCutoff_m)(rng);
    // The capsule's extreme point against w at x + gap w: its lower segment end, then the radius.
    const Eigen::Vector3d low = (R * c.a_m).dot(w_W) <= (R * c.b_m).dot(w_W) ? c.a_m : c.b_m;
    Eigen::Isometry3d X_WL = Eigen::Isometry3d::Identity();
    X_WL.linear() = R;
    X_WL.translation() = x_W + (gap + c.radius_m) * w_W - R * low;
    const Eigen::Isometry3d X_OL = obj.X_WO.inverse() * X_WL;
    const double oracle = capsuleMeshOracle(X_OL * c.a_m, X_OL * c.b_m, c.radius_m, obj.mesh);
    if (!(oracle > 1e-6 && oracle < kCutoff_m)) continue;  // touching or intersecting elsewhere
    const double d_fcl = fclCapsuleDistance(c, X_WL, obj_fcl, obj.X_WO);
    std::vector<LocalMinimum> snch;
    querySnchCapsule(c, X_WL, obj.tree, obj.mesh, obj.X_WO, kCutoff_m, scratch, snch);
    ++sum.poses;
    EXPECT_FALSE(snch.empty()) << obj.name << " vs link " << l << ", pose " << tried << ": oracle " << oracle;
    if (snch.empty()) continue;
    const LocalMinimum& m = *std::min_element(snch.begin(), snch.end(),
                                              [](const auto& a, const auto& b) { return a.distance_m < b.distance_m; });
    EXPECT_NEAR(m.distance_m, oracle, kTolerance_m) << obj.name << " vs link " << l << ", pose " << tried;
    EXPECT_NEAR(m.distance_m, d_fcl, kFclTolerance_m) << obj.name << " vs link " << l << ", pose " << tried;
    // The reported endpoints (local frames) are that far apart, the link's on the capsule.
    EXPECT_NEAR((obj.X_WO * m.p_O - X_WL * m.p_L).norm(), m.distance_m, 1e-12);
    const double s_param = closestSegmentParameter(c.a_m, c.b_m, m.p_L);
    EXPECT_NEAR((m.p_L - (c.a_m + s_param * (c.b_m - c.a_m))).norm(), c.radius_m, 1e-12);
    sum.max_oracle_error_m = std::max(sum.max_oracle_error_m, std::abs(m.distance_m - oracle));
    sum.max_fcl_error_m = std::max(sum.max_fcl_error_m, std::abs(m.distance_m - d_fcl));
    ++sum.object_feature[static_cast<std::size_t>(m.feature_object.kind)];
  }
  std::cout << obj.name << " (" << obj.mesh.numTriangles() << " triangles): " << sum.poses << " of " << tried
            << " poses compared; max |SNCH - oracle| = " << sum.max_oracle_error_m
            << " m, max |SNCH - FCL| = " << sum.max_fcl_error_m << " m; closest object feature: face "
            << sum.object_feature[0] << ", edge " << sum.object_feature[1] << ", vertex " << sum.object_feature[2]
            << "\n";
  EXPECT_EQ(sum.poses, poses) << obj.name;
  return sum;
}

TEST(FclDrcTest, CapsuleLinkDistancesEqualTheSegmentOracleAndFclOnDrcMeshesAndTubeFrames) {
  const arm::ArmModel& model = arm::test::defaultModel();
  const Scene scene = loadScene(arm::test::sourcePath("scenes/valve_wall.yaml"));
  CollisionWorld world = makeCollisionWorld(scene, model);
  // A second tube frame: 20 mm bars on 2 cm triangles, 0.5 x 0.4 m.
  world.addObject("tube_frame_20mm", makeRectangularFrame(0.5, 0.4, 0.02, 0.02, 0.02),
                  Eigen::Isometry3d(Eigen::AngleAxisd(0.4, Eigen::Vector3d(1.0, 2.0, 0.5).normalized())));
  int total = 0;
  int edge_or_vertex = 0;
  std::uint32_t seed = 20261201;
  for (const char* name : {"valve_wall", "wheel_valve", "opening_frame", "tube_frame_20mm"}) {
    const int o = world.objectIndex(name);
    ASSERT_GE(o, 0) << name;
    const CapsuleSummary sum = compareCapsulesWithOracles(world, world.object(o), 320, seed++);
    total += sum.poses;
    edge_or_vertex += sum.object_feature[1] + sum.object_feature[2];
  }
  RecordProperty("poses", total);
  EXPECT_GE(total, 1000);
  // Edge and vertex minima on the objects must be among the compared cases.
  EXPECT_GT(edge_or_vertex, total / 10);
}

}  // namespace
}  // namespace fullarm::haptics
