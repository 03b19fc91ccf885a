// Neighbour-rejection cones against brute force: whenever a direction lies inside the cone of
// a vertex or an edge, every neighbour triangle of that feature fails the first-order
// screening test of local descent, evaluated directly over the feature's triangles (in double,
// as local descent evaluates it, and in long double). Meshes: random small closed meshes, a
// box with random relief (peaks, pits and saddles), a link capsule, open folded sheets and a
// two-sided sheet (every triangle twice, once per winding).
#include "fullarm/haptics/neighbour_cones.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <random>

#include "fullarm/haptics/primitives.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

using Eigen::Vector3d;
using LongVector = Eigen::Matrix<long double, 3, 1>;

// A 10 x 10 x 4 cm box of 1 cm triangles with +-1.5 mm random relief on its top face.
TriMesh reliefBox(std::mt19937& rng) {
  const TriMesh box = makeBox({0.1, 0.1, 0.04}, 0.01);
  std::uniform_real_distribution<double> bump(-0.0015, 0.0015);
  std::vector<Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < box.numVertices(); ++i) {
    Vector3d p = box.vertex(i);
    if (p.z() > 0.0 && std::abs(p.x()) < 0.05 - 1e-9 && std::abs(p.y()) < 0.05 - 1e-9) p.z() += bump(rng);
    v.push_back(p);
  }
  for (int i = 0; i < box.numTriangles(); ++i) t.push_back(box.triangle(i));
  return TriMesh::build("relief box", std::move(v), std::move(t));
}

// Both windings of every triangle of `mesh`, moved away from the origin (larger coordinates).
TriMesh twoSided(const TriMesh& mesh) {
  std::vector<Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(mesh.vertex(i) + Vector3d(0.7, -0.4, 0.2));
  for (int i = 0; i < mesh.numTriangles(); ++i) {
    const Eigen::Vector3i& tri = mesh.triangle(i);
    t.push_back(tri);
    t.emplace_back(tri[0], tri[2], tri[1]);
  }
  return TriMesh::build("two-sided", std::move(v), std::move(t));
}

LongVector wide(const Vector3d& x) {
  return x.cast<long double>();
}

// Brute force: does some neighbour triangle of f pass the first-order screening for dir?
// Returns true when one passes in double (local descent's arithmetic) or in long double.
bool someNeighbourMayBeCloser(const TriMesh& mesh, const Feature& f, const Vector3d& dir) {
  if (f.kind == FeatureKind::kVertex) {
    const Vector3d& x = mesh.vertex(f.index);
    for (const int t : mesh.vertexTriangles(f.index)) {
      for (int k = 0; k < 3; ++k) {
        const int w = mesh.triangle(t)[k];
        if (w == f.index) continue;
        if (dir.dot(mesh.vertex(w)) > dir.dot(x)) return true;
        if (wide(dir).dot(wide(mesh.vertex(w)) - wide(x)) > 0.0L) return true;
      }
    }
    return false;
  }
  const auto ev = mesh.edgeVertices(f.index);
  const Vector3d& a = mesh.vertex(ev[0]);
  const Vector3d ab = mesh.vertex(ev[1]) - a;
  for (const int t : mesh.edgeTriangles(f.index)) {
    for (int k = 0; k < 3; ++k) {
      const int w = mesh.triangle(t)[k];
      if (w == ev[0] || w == ev[1]) continue;
      const Vector3d aw = mesh.vertex(w) - a;
      if (ab.squaredNorm() * dir.dot(aw) - aw.dot(ab) * dir.dot(ab) > 0.0) return true;
      const LongVector awl = wide(mesh.vertex(w)) - wide(a);
      const LongVector abl = wide(mesh.vertex(ev[1])) - wide(a);
      if (abl.squaredNorm() * wide(dir).dot(awl) - awl.dot(abl) * wide(dir).dot(abl) > 0.0L) return true;
    }
  }
  return false;
}

struct Tally {
  long rejected = 0;  // directions the cones rejected (each checked by brute force)
  long features_with_cone = 0;
  long features = 0;
};

// Directions around each feature's cone axis (angles 0-0.6 rad) and uniform ones.
void checkMesh(const TriMesh& mesh, std::mt19937& rng, Tally& tally) {
  const NeighbourCones cones = computeNeighbourCones(mesh);
  ASSERT_EQ(static_cast<int>(cones.vertex.size()), mesh.numVertices());
  ASSERT_EQ(static_cast<int>(cones.edge.size()), mesh.numEdges());
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> angle(0.0, 0.6);
  auto check = [&](const Feature& f, const Eigen::Vector4f& c) {
    ++tally.features;
    const Vector3d axis = c.head<3>().cast<double>();
    if (c[3] <= 1.5F) ++tally.features_with_cone;
    for (int s = 0; s < 24; ++s) {
      Vector3d dir = Vector3d(n(rng), n(rng), n(rng)).normalized();
      if (s < 20 && axis.norm() > 0.5) {
        // Rotate the axis by a random angle about a random perpendicular.
        const Vector3d perp = axis.cross(dir).normalized();
        dir = Eigen::AngleAxisd(angle(rng), perp) * axis.normalized();
      }
      if (!conesRejectAllNeighbours(cones, f, dir)) continue;
      ++tally.rejected;
      ASSERT_FALSE(someNeighbourMayBeCloser(mesh, f, dir))
          << mesh.source() << ": the cone of " << (f.kind == FeatureKind::kVertex ? "vertex " : "edge ") << f.index
          << " rejects a direction for which a neighbour passes the screening";
    }
  };
  for (int v = 0; v < mesh.numVertices(); ++v)
    check({FeatureKind::kVertex, v}, cones.vertex[static_cast<std::size_t>(v)]);
  for (int e = 0; e < mesh.numEdges(); ++e) check({FeatureKind::kEdge, e}, cones.edge[static_cast<std::size_t>(e)]);
  EXPECT_FALSE(conesRejectAllNeighbours(cones, {FeatureKind::kFace, 0}, Vector3d::UnitZ()));
}

TEST(NeighbourConesTest, RejectedDirectionsFailEveryNeighbourScreening) {
  std::mt19937 rng(2026);
  Tally tally;
  for (int i = 0; i < 40; ++i) checkMesh(test::randomSmallMesh(rng), rng, tally);
  for (int i = 0; i < 4; ++i) checkMesh(reliefBox(rng), rng, tally);
  checkMesh(makeCapsule({0, 0, 0}, {0, 0, 0.3}, 0.05, 16, 4), rng, tally);
  for (const double fold : {0.4, 1.6, 2.9}) {
    for (const bool outside : {false, true}) {
      test::FoldGrid g = test::foldGrid(fold, 6, outside);
      checkMesh(TriMesh::build("fold", std::move(g.vertices), std::move(g.triangles), 1e-9), rng, tally);
    }
  }
  checkMesh(twoSided(reliefBox(rng)), rng, tally);
  // The cones are exercised: many features of these meshes have one (flat box faces have
  // none), and a large share of the directions near the axes falls inside.
  EXPECT_GT(tally.features_with_cone, tally.features / 4);
  EXPECT_GT(tally.rejected, tally.features * 3);
  RecordProperty("features", static_cast<int>(tally.features));
  RecordProperty("features_with_cone", static_cast<int>(tally.features_with_cone));
  RecordProperty("rejected_directions", static_cast<int>(tally.rejected));
}

// Features whose neighbour directions do not fit in an open half-space have no cone: a flat
// vertex inside a plane (its one-ring edges span the plane) and an edge between two coplanar
// triangles.
TEST(NeighbourConesTest, FlatFeaturesHaveNoCone) {
  const TriMesh box = makeBox({0.1, 0.1, 0.04}, 0.01);
  const NeighbourCones cones = computeNeighbourCones(box);
  int flat_vertices = 0;
  int flat_edges = 0;
  for (int v = 0; v < box.numVertices(); ++v) {
    const Vector3d& p = box.vertex(v);
    if (p.z() > 0.0 && std::abs(p.x()) < 0.05 - 1e-9 && std::abs(p.y()) < 0.05 - 1e-9) {
      ++flat_vertices;
      EXPECT_GT(cones.vertex[static_cast<std::size_t>(v)][3], 1.5F) << "vertex " << v;
      EXPECT_FALSE(conesRejectAllNeighbours(cones, {FeatureKind::kVertex, v}, Vector3d::UnitZ()));
    }
  }
  for (int e = 0; e < box.numEdges(); ++e) {
    const auto ts = box.edgeTriangles(e);
    if (ts.size() == 2 && box.faceNormal(ts[0]).dot(box.faceNormal(ts[1])) > 1.0 - 1e-12) {
      ++flat_edges;
      EXPECT_GT(cones.edge[static_cast<std::size_t>(e)][3], 1.5F) << "edge " << e;
    }
  }
  EXPECT_GT(flat_vertices, 50);
  EXPECT_GT(flat_edges, 100);
  // A box corner is a strict peak: its cone holds the diagonal direction.
  int corner = -1;
  for (int v = 0; v < box.numVertices(); ++v) {
    if ((box.vertex(v) - Vector3d(0.05, 0.05, 0.02)).norm() < 1e-12) corner = v;
  }
  ASSERT_GE(corner, 0);
  EXPECT_TRUE(conesRejectAllNeighbours(cones, {FeatureKind::kVertex, corner}, Vector3d(1, 1, 1).normalized()));
}

}  // namespace
}  // namespace fullarm::haptics
