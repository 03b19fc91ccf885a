// SNCH normal cones against the normal cones of the mesh features, computed by brute force from
// the adjacency: every direction u that a local minimum on a triangle can have (u in the exact
// normal cone of its face, of one of its edges or of one of its vertices) must lie in the cone,
// or double cone, of the triangle's leaf and of every ancestor of that leaf. The query prunes
// by these cones, so a cone that misses a feasible direction loses minima whose direction lies
// there.
//
// The directions are sampled, not constructed from the spanning rays the implementation uses:
// a Fibonacci sphere for the pointed vertex cones, and a fine angle grid in the plane
// perpendicular to every edge (edge cones, and the vertex cones of vertices on a fold line,
// which are planar wedges of measure zero on the sphere). A direction is feasible when it
// satisfies the defining inequalities u . e <= 0 for every direction e from the feature into
// an incident triangle, and is seen from outside (u . n >= 0 for the feature's pseudo-normal,
// condition 2 of snch.hpp; the pseudo-normals of a double-sided sheet are zero).
//
// The double-sided folded sheets are where the double cones are built: a vertex or an edge on
// the fold has a wedge of directions that, for some fold angles, straddles the plane of a
// triangle. A construction that turns each spanning ray to the face normal's side separately
// (instead of rejecting a straddling feature) makes a double cone that misses the wedge's
// in-plane directions; the brute-force comparison of SnchOpenMeshTest did not catch that
// mutation, this test does (checked by applying it).
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/snch.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

using Eigen::Vector3d;

// A sheet of two 0.1 x 0.1 m panels (n x n squares each) meeting along the x axis at `fold`
// radians between the panels, every triangle also present with the opposite winding (as the
// DRC CAD exports are). Interior fold vertices (0 < x < 0.1) are not on the rim.
TriMesh doubleSidedFold(double fold, int n) {
  test::FoldGrid g = test::foldGrid(fold, n, /*face_outside=*/false);
  std::vector<Vector3d>& v = g.vertices;
  std::vector<Eigen::Vector3i>& t = g.triangles;
  const std::size_t one_side = t.size();
  for (std::size_t k = 0; k < one_side; ++k) t.emplace_back(t[k][0], t[k][2], t[k][1]);
  return TriMesh::build("double-sided fold", std::move(v), std::move(t), 1e-9);
}

// Does the node's cone (or double cone) hold direction u (unit)? Tolerance 1e-9 rad: the
// cones must hold the exact feature cones up to rounding (the query adds kConeSlack_rad).
bool coneHolds(const SnchNode& node, const Vector3d& u) {
  if (node.cone_half_angle_rad >= std::numbers::pi) return true;
  double c = node.cone_axis.dot(u);
  if (node.cone_two_sided) c = std::abs(c);
  const double angle = std::atan2(node.cone_axis.cross(u).norm(), c);
  return angle <= node.cone_half_angle_rad + 1e-9;
}

// Root-to-leaf path of every triangle: path[t] = node indices from the root to t's leaf.
std::vector<std::vector<int>> leafPaths(const SnchTree& tree, int num_triangles) {
  std::vector<std::vector<int>> paths(static_cast<std::size_t>(num_triangles));
  std::vector<std::vector<int>> stack{{0}};
  while (!stack.empty()) {
    const std::vector<int> path = stack.back();
    stack.pop_back();
    const SnchNode& node = tree.nodes[static_cast<std::size_t>(path.back())];
    if (node.isLeaf()) {
      paths[static_cast<std::size_t>(node.triangle)] = path;
      continue;
    }
    for (const int child : {node.left, node.right}) {
      std::vector<int> p = path;
      p.push_back(child);
      stack.push_back(std::move(p));
    }
  }
  return paths;
}

// Candidate directions: a Fibonacci sphere, and a circle of directions perpendicular to each
// of the given axes.
std::vector<Vector3d> sampleDirections(const std::vector<Vector3d>& axes) {
  std::vector<Vector3d> dirs;
  const int n_sphere = 2000;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < n_sphere; ++i) {
    const double z = 1.0 - 2.0 * (i + 0.5) / n_sphere;
    const double r = std::sqrt(1.0 - z * z);
    dirs.emplace_back(r * std::cos(golden * i), r * std::sin(golden * i), z);
  }
  const int n_circle = 360;
  for (const Vector3d& a : axes) {
    const Vector3d e1 = a.unitOrthogonal();
    const Vector3d e2 = a.cross(e1);
    for (int i = 0; i < n_circle; ++i) {
      const double phi = 2.0 * std::numbers::pi * i / n_circle;
      dirs.push_back(std::cos(phi) * e1 + std::sin(phi) * e2);
    }
  }
  return dirs;
}

// Every direction from vertex v into its incident triangles' other vertices (normalised).
std::vector<Vector3d> vertexEdgeDirections(const TriMesh& mesh, int v) {
  std::vector<Vector3d> dirs;
  for (const int s : mesh.vertexTriangles(v)) {
    for (int k = 0; k < 3; ++k) {
      const int w = mesh.triangle(s)[k];
      if (w != v) dirs.push_back((mesh.vertex(w) - mesh.vertex(v)).normalized());
    }
  }
  return dirs;
}

struct CheckCounts {
  long feasible = 0;        // (feature, direction) pairs in a feature's normal cone
  long missed = 0;          // of those, not held by the leaf or an ancestor
  long wedge_in_plane = 0;  // feasible directions within 5 degrees of the triangle's plane
};

// Checks every triangle of `mesh`: each feasible direction of its face, edges and vertices
// must be held by every cone on the path from the root to its leaf.
CheckCounts checkMesh(const TriMesh& mesh) {
  const SnchTree tree = buildSnchTree(mesh);
  const auto paths = leafPaths(tree, mesh.numTriangles());
  CheckCounts counts;
  auto check = [&](int t, const Vector3d& u, const char* what, int feature) {
    ++counts.feasible;
    if (std::abs(u.dot(mesh.faceNormal(t))) < std::sin(5.0 * std::numbers::pi / 180.0)) ++counts.wedge_in_plane;
    for (const int node : paths[static_cast<std::size_t>(t)]) {
      if (!coneHolds(tree.nodes[static_cast<std::size_t>(node)], u)) {
        ++counts.missed;
        ADD_FAILURE() << mesh.source() << ": triangle " << t << ", " << what << " " << feature << ": direction ("
                      << u.transpose() << ") of its normal cone is outside the cone of node " << node;
        return;
      }
    }
  };
  constexpr double kFeasible = 1e-12;  // u . e <= kFeasible (unit vectors)
  // Condition (2) of a local minimum (snch.hpp): seen from outside, u . n >= 0 for the
  // feature's pseudo-normal (zero on double-sided sheets, where both sides count).
  auto outside = [&mesh](const Vector3d& u, const Feature& f) {
    return u.dot(mesh.featureNormal(f)) >= -kOutsideCosineTolerance;
  };
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    check(t, mesh.faceNormal(t), "face", t);
    std::vector<Vector3d> axes;
    for (int k = 0; k < 3; ++k) {
      const auto ev = mesh.edgeVertices(mesh.triangleEdge(t, k));
      axes.push_back((mesh.vertex(ev[1]) - mesh.vertex(ev[0])).normalized());
    }
    // Vertices: every sampled direction with u . e <= 0 for every edge leaving the vertex. A
    // vertex with a direction e and -e among its edges (on a fold line) has a planar cone:
    // the circles perpendicular to the triangle's edges sample it.
    const std::vector<Vector3d> dirs = sampleDirections(axes);
    for (int k = 0; k < 3; ++k) {
      const int v = mesh.triangle(t)[k];
      const std::vector<Vector3d> out = vertexEdgeDirections(mesh, v);
      for (const Vector3d& u : dirs) {
        bool feasible = true;
        for (const Vector3d& e : out) feasible = feasible && u.dot(e) <= kFeasible;
        if (feasible && outside(u, {FeatureKind::kVertex, v})) check(t, u, "vertex", v);
      }
    }
    // Edges: directions perpendicular to the edge with u . d <= 0 for the in-plane direction d
    // into every incident triangle.
    for (int k = 0; k < 3; ++k) {
      const int e = mesh.triangleEdge(t, k);
      const auto ev = mesh.edgeVertices(e);
      const Vector3d p0 = mesh.vertex(ev[0]);
      const Vector3d along = (mesh.vertex(ev[1]) - p0).normalized();
      std::vector<Vector3d> into;
      for (const int s : mesh.edgeTriangles(e)) {
        for (int m = 0; m < 3; ++m) {
          const int w = mesh.triangle(s)[m];
          if (w == ev[0] || w == ev[1]) continue;
          const Vector3d d = mesh.vertex(w) - p0;
          into.push_back((d - d.dot(along) * along).normalized());
        }
      }
      for (const Vector3d& u : sampleDirections({along})) {
        if (std::abs(u.dot(along)) > kFeasible) continue;
        bool feasible = true;
        for (const Vector3d& d : into) feasible = feasible && u.dot(d) <= kFeasible;
        if (feasible && outside(u, {FeatureKind::kEdge, e})) check(t, u, "edge", e);
      }
    }
  }
  return counts;
}

TEST(SnchConeTest, DoubleSidedFoldConesHoldEveryFeatureNormalDirection) {
  // Fold angles between the panels from 15 to 165 degrees: acute folds have an outside wedge
  // wider than 90 degrees, obtuse ones a narrow wedge straddling the planes of the panels.
  long feasible = 0;
  long in_plane = 0;
  for (int deg = 15; deg <= 165; deg += 15) {
    const CheckCounts c = checkMesh(doubleSidedFold(deg * std::numbers::pi / 180.0, 3));
    EXPECT_EQ(c.missed, 0) << "fold " << deg << " deg";
    feasible += c.feasible;
    in_plane += c.wedge_in_plane;
  }
  // The sample must reach the directions the mutation loses: near a triangle's own plane.
  EXPECT_GT(feasible, 10000);
  EXPECT_GT(in_plane, 100);
}

TEST(SnchConeTest, ClosedMeshConesHoldEveryFeatureNormalDirection) {
  // One-sided leaves (cones around the one-ring normals) on closed primitives with convex and
  // reflex edges and vertices.
  for (const TriMesh& mesh : {makeBox({0.1, 0.06, 0.04}, 0.02), makeRectangularFrame(0.3, 0.2, 0.04, 0.03, 0.02),
                              makeIBeam(0.1, 0.08, 0.01, 0.008, 0.2, 0.04), makeCylinder(0.03, 0.1, 12, 0.05)}) {
    const CheckCounts c = checkMesh(mesh);
    EXPECT_EQ(c.missed, 0) << mesh.source();
    EXPECT_GT(c.feasible, 1000) << mesh.source();
  }
}

}  // namespace
}  // namespace fullarm::haptics
