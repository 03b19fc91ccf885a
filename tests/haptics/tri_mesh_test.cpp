// TriMesh: adjacency against hand-counted meshes and Euler's formula, validation errors,
// documented repairs, and mutated inputs that must give MeshError, never a crash.
#include "fullarm/haptics/tri_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <set>

namespace fullarm::haptics {
namespace {

// Unit tetrahedron, outward winding.
TriMesh tetrahedron() {
  return TriMesh::build("tetra", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
                        {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}});
}

TEST(TriMeshTest, TetrahedronAdjacencyMatchesEuler) {
  const TriMesh m = tetrahedron();
  EXPECT_EQ(m.numVertices(), 4);
  EXPECT_EQ(m.numTriangles(), 4);
  EXPECT_EQ(m.numEdges(), 6);  // V - E + F = 2
  EXPECT_EQ(m.boundaryEdgeCount(), 0);
  EXPECT_EQ(m.nonManifoldEdgeCount(), 0);
  for (int e = 0; e < m.numEdges(); ++e) EXPECT_EQ(m.edgeTriangles(e).size(), 2u);
  for (int v = 0; v < 4; ++v) EXPECT_EQ(m.vertexTriangles(v).size(), 3u);
  // Every triangle edge joins the right vertices and lists the triangle.
  for (int t = 0; t < m.numTriangles(); ++t) {
    for (int k = 0; k < 3; ++k) {
      const int e = m.triangleEdge(t, k);
      const auto ev = m.edgeVertices(e);
      const int a = m.triangle(t)[k];
      const int b = m.triangle(t)[(k + 1) % 3];
      EXPECT_EQ(ev[0], std::min(a, b));
      EXPECT_EQ(ev[1], std::max(a, b));
      const auto tris = m.edgeTriangles(e);
      EXPECT_NE(std::find(tris.begin(), tris.end(), t), tris.end());
    }
  }
  // Outward normals: each points away from the centroid.
  const Eigen::Vector3d c(0.25, 0.25, 0.25);
  for (int t = 0; t < 4; ++t) {
    EXPECT_NEAR(m.faceNormal(t).norm(), 1.0, 1e-15);
    EXPECT_GT(m.faceNormal(t).dot(m.vertex(m.triangle(t)[0]) - c), 0.0);
  }
  // Vertex 0 pseudo-normal of the corner (0,0,0) is -(1,1,1)/sqrt(3) by symmetry.
  const Eigen::Vector3d n0 = m.featureNormal({FeatureKind::kVertex, 0});
  EXPECT_NEAR((n0 + Eigen::Vector3d::Ones().normalized()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(m.area(), 1.5 + std::sqrt(3.0) / 2.0, 1e-14);
  // featureTriangles of a face is that face.
  const auto ft = m.featureTriangles({FeatureKind::kFace, 2});
  ASSERT_EQ(ft.size(), 1u);
  EXPECT_EQ(ft[0], 2);
}

TEST(TriMeshTest, NonFiniteCoordinateNamesVertexAndSource) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  try {
    (void)TriMesh::build("walls.dae", {{0, 0, 0}, {1, 0, nan}, {0, 1, 0}}, {{0, 1, 2}});
    FAIL() << "expected MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("walls.dae"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("vertex 1"), std::string::npos) << e.what();
    EXPECT_EQ(e.source(), "walls.dae");
  }
}

// Found by UBSan on a mutated PLY file: a coordinate of 1e10 m at a 1 um weld tolerance (2^53 cells out) has no
// integer cell index. It must be a MeshError naming the vertex, not undefined behaviour.
TEST(TriMeshTest, CoordinateTooLargeToWeldNamesVertex) {
  try {
    (void)TriMesh::build("huge.ply", {{0, 0, 0}, {1e10, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}, 1e-6);
    FAIL() << "expected MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("vertex 1"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("too far from the origin to weld"), std::string::npos) << e.what();
  }
  // Without welding the same coordinates are accepted (they are finite).
  EXPECT_NO_THROW((void)TriMesh::build("huge.ply", {{0, 0, 0}, {1e10, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}));
}

TEST(TriMeshTest, IndexOutOfRangeNamesTriangle) {
  try {
    (void)TriMesh::build("b", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}, {0, 3, 1}});
    FAIL() << "expected MeshError";
  } catch (const MeshError& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 1 references vertex 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)TriMesh::build("b", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, -1, 2}}), MeshError);
}

TEST(TriMeshTest, DegenerateTrianglesAreDroppedAndCounted) {
  const TriMesh m = TriMesh::build("d", {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {2, 0, 0}},
                                   {{0, 1, 2}, {0, 0, 1}, {0, 1, 3}});  // repeated index; collinear
  EXPECT_EQ(m.numTriangles(), 1);
  EXPECT_EQ(m.repairedDegenerateCount(), 2);
  EXPECT_THROW((void)TriMesh::build("e", {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}}, {{0, 1, 2}}), MeshError);
  EXPECT_THROW((void)TriMesh::build("e", {}, {}), MeshError);
}

TEST(TriMeshTest, NonManifoldEdgeListsAllTriangles) {
  // Three fins sharing the edge (0,1).
  const TriMesh m = TriMesh::build("fins", {{0, 0, 0}, {0, 0, 1}, {1, 0, 0}, {-1, 1, 0}, {-1, -1, 0}},
                                   {{0, 1, 2}, {0, 1, 3}, {1, 0, 4}});
  EXPECT_EQ(m.nonManifoldEdgeCount(), 1);
  const int e = m.triangleEdge(0, 0);
  EXPECT_EQ(m.edgeTriangles(e).size(), 3u);
  EXPECT_EQ(m.boundaryEdgeCount(), 6);
}

TEST(TriMeshTest, WeldingMergesSeamVertices) {
  // Two triangles of a square with duplicated seam vertices.
  std::vector<Eigen::Vector3d> v{{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 0, 1e-9}, {1, 1, 0}, {0, 1, 0}};
  std::vector<Eigen::Vector3i> t{{0, 1, 2}, {3, 4, 5}};
  const TriMesh unwelded = TriMesh::build("sq", v, t);
  EXPECT_EQ(unwelded.numEdges(), 6);
  const TriMesh welded = TriMesh::build("sq", v, t, 1e-6);
  EXPECT_EQ(welded.numVertices(), 4);
  EXPECT_EQ(welded.weldedVertexCount(), 2);
  EXPECT_EQ(welded.numEdges(), 5);
  EXPECT_EQ(welded.boundaryEdgeCount(), 4);
  EXPECT_THROW((void)TriMesh::build("sq", v, t, -1.0), MeshError);
}

// Fuzz-style: random mutations of a valid mesh either build or throw MeshError.
TEST(TriMeshTest, MutatedInputsBuildOrThrowMeshError) {
  std::mt19937 rng(1234);
  std::uniform_int_distribution<int> pick(0, 5);
  const std::vector<Eigen::Vector3d> v0{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<Eigen::Vector3i> t0{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  int errors = 0;
  for (int trial = 0; trial < 500; ++trial) {
    auto v = v0;
    auto t = t0;
    const int what = pick(rng);
    std::uniform_int_distribution<int> vi(0, static_cast<int>(v.size()) - 1);
    std::uniform_int_distribution<int> ti(0, static_cast<int>(t.size()) - 1);
    switch (what) {
      case 0:
        v[static_cast<std::size_t>(vi(rng))][trial % 3] = std::numeric_limits<double>::infinity();
        break;
      case 1:
        t[static_cast<std::size_t>(ti(rng))][trial % 3] = std::uniform_int_distribution<int>(-5, 10)(rng);
        break;
      case 2:
        t.resize(static_cast<std::size_t>(ti(rng)));
        break;
      case 3:
        v.resize(static_cast<std::size_t>(vi(rng)));
        break;
      case 4:
        t.push_back(t[static_cast<std::size_t>(ti(rng))]);
        break;
      default:
        v[static_cast<std::size_t>(vi(rng))] = v[static_cast<std::size_t>(vi(rng))];
        break;
    }
    try {
      const TriMesh m = TriMesh::build("fuzz", v, t, trial % 2 == 0 ? 0.0 : 1e-3);
      EXPECT_GT(m.numTriangles(), 0);
    } catch (const MeshError& e) {
      ++errors;
      EXPECT_NE(std::string(e.what()).find("fuzz: "), std::string::npos);
    }
  }
  EXPECT_GT(errors, 0);
}

}  // namespace
}  // namespace fullarm::haptics
