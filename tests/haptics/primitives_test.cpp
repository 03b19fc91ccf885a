// Primitive builders: closed 2-manifolds (every edge shared by two triangles) with the Euler
// characteristic of their topology, outward winding, and enclosed volume equal to the
// analytic volume of the solid (divergence theorem).
#include "fullarm/haptics/primitives.hpp"

#include <gtest/gtest.h>

#include <numbers>

namespace fullarm::haptics {
namespace {

double enclosedVolume(const TriMesh& m) {
  double v = 0.0;
  for (int t = 0; t < m.numTriangles(); ++t) {
    const auto& tri = m.triangle(t);
    v += m.vertex(tri[0]).dot(m.vertex(tri[1]).cross(m.vertex(tri[2]))) / 6.0;
  }
  return v;
}

void expectClosed(const TriMesh& m, int euler) {
  EXPECT_EQ(m.boundaryEdgeCount(), 0) << m.source();
  EXPECT_EQ(m.nonManifoldEdgeCount(), 0) << m.source();
  EXPECT_EQ(m.numVertices() - m.numEdges() + m.numTriangles(), euler) << m.source();
  // Consistent winding: each edge is traversed once in each direction.
  for (int e = 0; e < m.numEdges(); ++e) {
    const auto tris = m.edgeTriangles(e);
    ASSERT_EQ(tris.size(), 2u);
    int forward = 0;
    for (int t : tris) {
      for (int k = 0; k < 3; ++k) {
        if (m.triangleEdge(t, k) == e && m.triangle(t)[k] == m.edgeVertices(e)[0]) ++forward;
      }
    }
    EXPECT_EQ(forward, 1);
  }
}

TEST(PrimitivesTest, BoxIsClosedWithExactVolumeAtEveryResolution) {
  for (double res : {1.0, 0.1, 0.03}) {
    const TriMesh box = makeBox({0.4, 0.3, 0.2}, res);
    expectClosed(box, 2);
    EXPECT_NEAR(enclosedVolume(box), 0.4 * 0.3 * 0.2, 1e-14);
    EXPECT_NEAR(box.area(), 2 * (0.12 + 0.08 + 0.06), 1e-13);
  }
  EXPECT_EQ(makeBox({1, 1, 1}, 0.5).numTriangles(), 6 * 8);
  EXPECT_THROW((void)makeBox({1, -1, 1}, 0.5), MeshError);
  EXPECT_THROW((void)makeBox({1, 1, 1}, 0.0), MeshError);
}

TEST(PrimitivesTest, CylinderVolumeIsItsPolygonPrism) {
  const int n = 24;
  const TriMesh c = makeCylinder(0.1, 0.5, n, 0.05);
  expectClosed(c, 2);
  const double polygon_area = 0.5 * n * 0.01 * std::sin(2 * std::numbers::pi / n);
  EXPECT_NEAR(enclosedVolume(c), polygon_area * 0.5, 1e-14);
}

TEST(PrimitivesTest, CapsuleVerticesLieOnTheRoundedSurface) {
  const Eigen::Vector3d a(0.1, -0.2, 0.3), b(0.4, 0.1, -0.2);
  const TriMesh c = makeCapsule(a, b, 0.05, 16, 4);
  expectClosed(c, 2);
  for (int v = 0; v < c.numVertices(); ++v) {
    const Eigen::Vector3d p = c.vertex(v);
    const double s = std::clamp((p - a).dot(b - a) / (b - a).squaredNorm(), 0.0, 1.0);
    EXPECT_NEAR((p - (a + s * (b - a))).norm(), 0.05, 1e-12);
  }
  const double exact = std::numbers::pi * 0.0025 * ((b - a).norm() + 4.0 / 3.0 * 0.05);
  EXPECT_GT(enclosedVolume(c), 0.8 * exact);
  EXPECT_LT(enclosedVolume(c), exact);
  // Zero-length capsule is a sphere (welded equators).
  expectClosed(makeCapsule(a, a, 0.05, 8, 3), 2);
}

TEST(PrimitivesTest, FrameHasGenusOneAndExactVolume) {
  const TriMesh f = makeRectangularFrame(1.0, 0.8, 0.1, 0.05, 0.04);
  expectClosed(f, 0);
  EXPECT_NEAR(enclosedVolume(f), (1.0 * 0.8 - 0.8 * 0.6) * 0.05, 1e-14);
  EXPECT_THROW((void)makeRectangularFrame(1.0, 0.8, 0.4, 0.05, 0.04), MeshError);
}

TEST(PrimitivesTest, IBeamIsClosedWithExactVolume) {
  const TriMesh i = makeIBeam(0.2, 0.1, 0.02, 0.01, 1.0, 0.03);
  expectClosed(i, 2);
  EXPECT_NEAR(enclosedVolume(i), (2 * 0.1 * 0.02 + 0.01 * 0.16) * 1.0, 1e-14);
}

}  // namespace
}  // namespace fullarm::haptics
