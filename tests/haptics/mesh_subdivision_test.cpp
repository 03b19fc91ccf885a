// Midpoint subdivision and long-edge refinement: triangle/vertex counts from Euler's formula,
// exact area, closed meshes stay closed (no T-junctions), every new vertex lies on the original
// surface, and edge lengths end below the limit.
#include "fullarm/haptics/mesh_subdivision.hpp"

#include <gtest/gtest.h>

#include <random>

#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/primitives.hpp"

namespace fullarm::haptics {
namespace {

constexpr double kAreaTolerance = 1e-12;
// A point on a 2 m sliver triangle, measured by point-triangle distance in double precision.
constexpr double kOnSurface = 1e-11;

double distanceToMesh(const TriMesh& mesh, const Eigen::Vector3d& p) {
  double best = 1e300;
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    const Eigen::Vector3i& tri = mesh.triangle(t);
    best = std::min(best,
                    closestPointTriangle(p, mesh.vertex(tri[0]), mesh.vertex(tri[1]), mesh.vertex(tri[2])).distance_m);
  }
  return best;
}

// Random points on the surface of `mesh` (area-uniform per triangle choice is not needed).
std::vector<Eigen::Vector3d> surfaceSamples(const TriMesh& mesh, int count, std::mt19937& rng) {
  std::uniform_int_distribution<int> tri(0, mesh.numTriangles() - 1);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) {
    const Eigen::Vector3i& t = mesh.triangle(tri(rng));
    double a = u(rng);
    double b = u(rng);
    if (a + b > 1.0) {
      a = 1.0 - a;
      b = 1.0 - b;
    }
    points.push_back(mesh.vertex(t[0]) + a * (mesh.vertex(t[1]) - mesh.vertex(t[0])) +
                     b * (mesh.vertex(t[2]) - mesh.vertex(t[0])));
  }
  return points;
}

void expectSameSurface(const TriMesh& original, const TriMesh& refined) {
  // Both ways: refined vertices and samples lie on the original, original samples on the refined.
  std::mt19937 rng(5);
  for (int v = 0; v < refined.numVertices(); v += std::max(1, refined.numVertices() / 200)) {
    ASSERT_LT(distanceToMesh(original, refined.vertex(v)), kOnSurface) << "vertex " << v;
  }
  for (const Eigen::Vector3d& p : surfaceSamples(refined, 100, rng)) ASSERT_LT(distanceToMesh(original, p), kOnSurface);
  for (const Eigen::Vector3d& p : surfaceSamples(original, 100, rng)) ASSERT_LT(distanceToMesh(refined, p), kOnSurface);
}

TEST(MeshSubdivisionTest, MidpointSubdivisionOfABoxFollowsEulerAndKeepsTheSurface) {
  const TriMesh box = makeBox({0.4, 0.2, 0.1}, 1.0);  // 12 triangles
  ASSERT_EQ(box.numTriangles(), 12);
  TriMesh previous = box;
  for (int levels = 1; levels <= 3; ++levels) {
    const TriMesh sub = subdivideMidpoint(box, levels);
    EXPECT_EQ(sub.numTriangles(), 12 << (2 * levels));
    // One new vertex per edge of the previous level; closed genus-0 surface: V - E + F = 2.
    EXPECT_EQ(sub.numVertices(), previous.numVertices() + previous.numEdges());
    EXPECT_EQ(sub.numVertices() - sub.numEdges() + sub.numTriangles(), 2);
    EXPECT_EQ(sub.boundaryEdgeCount(), 0);
    EXPECT_EQ(sub.nonManifoldEdgeCount(), 0);
    EXPECT_NEAR(sub.area(), box.area(), kAreaTolerance);
    EXPECT_NEAR(maxEdgeLength(sub), maxEdgeLength(box) / (1 << levels), 1e-15);
    // Normals are inherited: every child triangle's normal equals an axis direction of the box.
    for (int t = 0; t < sub.numTriangles(); ++t) EXPECT_NEAR(sub.faceNormal(t).cwiseAbs().maxCoeff(), 1.0, 1e-12);
    previous = sub;
  }
  expectSameSurface(box, subdivideMidpoint(box, 2));
  EXPECT_EQ(subdivideMidpoint(box, 0).numTriangles(), 12);
  EXPECT_THROW((void)subdivideMidpoint(box, -1), MeshError);
  EXPECT_THROW((void)subdivideMidpoint(box, 15), MeshError);  // 12 * 4^15 > 2^31
}

TEST(MeshSubdivisionTest, LongEdgeRefinementConformsAndOnlyRefinesLongEdges) {
  // A closed sliver-rich solid: a long thin box with single-triangle faces (edges up to ~2 m).
  const TriMesh sliver = makeBox({2.0, 0.02, 0.01}, 10.0);
  ASSERT_EQ(sliver.numTriangles(), 12);
  for (double limit : {0.5, 0.1, 0.013}) {
    SCOPED_TRACE(limit);
    const TriMesh refined = refineLongEdges(sliver, limit);
    EXPECT_LE(maxEdgeLength(refined), limit);
    EXPECT_EQ(refined.boundaryEdgeCount(), 0);  // no T-junction opened a crack
    EXPECT_EQ(refined.nonManifoldEdgeCount(), 0);
    EXPECT_EQ(refined.numVertices() - refined.numEdges() + refined.numTriangles(), 2);
    EXPECT_NEAR(refined.area(), sliver.area(), kAreaTolerance);
    expectSameSurface(sliver, refined);
  }
  // Nothing to do: a mesh whose edges are all short comes back unchanged.
  const TriMesh fine = makeBox({0.1, 0.1, 0.1}, 0.05);
  const TriMesh same = refineLongEdges(fine, 1.0);
  ASSERT_EQ(same.numTriangles(), fine.numTriangles());
  for (int v = 0; v < fine.numVertices(); ++v) EXPECT_EQ(same.vertex(v), fine.vertex(v));
  EXPECT_THROW((void)refineLongEdges(fine, 0.0), MeshError);
  EXPECT_THROW((void)refineLongEdges(fine, std::numeric_limits<double>::quiet_NaN()), MeshError);
}

}  // namespace
}  // namespace fullarm::haptics
