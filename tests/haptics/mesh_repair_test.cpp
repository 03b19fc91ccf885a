// collapseDoubleSidedSolids against meshes whose outward copy is known: the primitive builders'
// closed, outward-wound solids written a second time in the opposite winding (in shuffled
// order, the reversed copy sometimes first) must come back as exactly the builders' triangles;
// open double-sided sheets, non-manifold parts and single-sided meshes must come back
// unchanged; the surface (distance from any point) must not change. On the DRC files: the
// valve wall's kept copy encloses the plywood sheet's volume (published size), the wheel is
// collapsed despite its cracks (the repository's copies under scenes/meshes/gazebo-drc).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <random>
#include <set>
#include <vector>

#include "fullarm/haptics/geometry.hpp"
#include "fullarm/haptics/mesh_import.hpp"
#include "fullarm/haptics/mesh_repair.hpp"
#include "haptics_test_util.hpp"

namespace fullarm::haptics {
namespace {

using Tri = std::array<int, 3>;

// A triangle as a rotation-invariant key that keeps its winding: smallest index first.
Tri canonical(const Eigen::Vector3i& t) {
  int k = 0;
  if (t[1] < t[k]) k = 1;
  if (t[2] < t[k]) k = 2;
  return {t[k], t[(k + 1) % 3], t[(k + 2) % 3]};
}

std::multiset<Tri> orientedTriangles(const TriMesh& m) {
  std::multiset<Tri> s;
  for (int t = 0; t < m.numTriangles(); ++t) s.insert(canonical(m.triangle(t)));
  return s;
}

std::vector<Eigen::Vector3d> verticesOf(const TriMesh& m) {
  std::vector<Eigen::Vector3d> v;
  for (int i = 0; i < m.numVertices(); ++i) v.push_back(m.vertex(i));
  return v;
}

// `parts` (each a list of triangles over one shared vertex array) written twice, once per
// winding, in a shuffled order: the exporter's double-sided form.
TriMesh doubleSided(const std::vector<Eigen::Vector3d>& vertices, const std::vector<Eigen::Vector3i>& tris,
                    std::mt19937& rng) {
  std::vector<Eigen::Vector3i> all = tris;
  for (const auto& t : tris) all.emplace_back(t[0], t[2], t[1]);
  std::shuffle(all.begin(), all.end(), rng);
  return TriMesh::build("double-sided", vertices, all);
}

std::vector<Eigen::Vector3i> trianglesOf(const TriMesh& m, int offset = 0) {
  std::vector<Eigen::Vector3i> t;
  for (int i = 0; i < m.numTriangles(); ++i) t.push_back(m.triangle(i) + Eigen::Vector3i::Constant(offset));
  return t;
}

double enclosedVolume(const TriMesh& m) {
  double v = 0.0;
  for (int t = 0; t < m.numTriangles(); ++t) {
    const auto& tri = m.triangle(t);
    v += m.vertex(tri[0]).dot(m.vertex(tri[1]).cross(m.vertex(tri[2]))) / 6.0;
  }
  return v;
}

// Distance from p to the surface, over every triangle.
double surfaceDistance(const TriMesh& m, const Eigen::Vector3d& p) {
  double best = std::numeric_limits<double>::infinity();
  for (int t = 0; t < m.numTriangles(); ++t) {
    const auto& tri = m.triangle(t);
    best = std::min(best, squaredDistancePointTriangle(p, m.vertex(tri[0]), m.vertex(tri[1]), m.vertex(tri[2])));
  }
  return std::sqrt(best);
}

TEST(MeshRepair, DoubleSidedPrimitiveSolidsComeBackAsTheBuildersOutwardTriangles) {
  std::mt19937 rng(5);
  const std::vector<TriMesh> solids = {makeBox({0.2, 0.1, 0.05}, 0.04), makeCapsule({0, 0, 0}, {0, 0, 0.2}, 0.04, 8, 2),
                                       makeCylinder(0.05, 0.3, 10, 0.1), makeIBeam(0.12, 0.08, 0.015, 0.01, 0.2, 0.1),
                                       makeRectangularFrame(0.2, 0.16, 0.04, 0.03, 0.08)};
  for (const TriMesh& solid : solids) {
    ASSERT_GT(enclosedVolume(solid), 0.0) << solid.source() << ": the builder's winding is the outward reference";
    for (int trial = 0; trial < 4; ++trial) {
      const TriMesh twice = doubleSided(verticesOf(solid), trianglesOf(solid), rng);
      ASSERT_GT(twice.nonManifoldEdgeCount(), 0);
      DoubleSidedRepair rep;
      const TriMesh once = collapseDoubleSidedSolids(twice, &rep);
      EXPECT_EQ(rep.solids_collapsed, 1) << solid.source();
      EXPECT_EQ(rep.triangles_removed, solid.numTriangles());
      EXPECT_EQ(rep.parts_kept_double_sided, 0);
      EXPECT_EQ(rep.solids_with_holes, 0);
      EXPECT_EQ(orientedTriangles(once), orientedTriangles(solid)) << solid.source() << ", trial " << trial;
      EXPECT_EQ(once.nonManifoldEdgeCount(), 0);
      EXPECT_EQ(once.boundaryEdgeCount(), 0);
    }
  }
}

TEST(MeshRepair, OpenSheetsNonManifoldPartsAndSingleSidedMeshesAreKept) {
  std::mt19937 rng(6);
  // A folded open sheet, double-sided: nothing encloses a volume, both sides stay.
  test::FoldGrid g = test::foldGrid(1.0, 4, /*face_outside=*/true);
  const TriMesh sheet = TriMesh::build("sheet", g.vertices, g.triangles, 1e-9);
  const TriMesh sheet2 = doubleSided(verticesOf(sheet), trianglesOf(sheet), rng);
  DoubleSidedRepair rep;
  EXPECT_EQ(orientedTriangles(collapseDoubleSidedSolids(sheet2, &rep)), orientedTriangles(sheet2));
  EXPECT_EQ(rep.solids_collapsed, 0);
  EXPECT_EQ(rep.parts_kept_double_sided, 1);

  // Three double-sided pages on one spine: six triangles per spine edge, not a 2-manifold.
  const std::vector<Eigen::Vector3d> v = {{0, 0, 0}, {0, 0, 1}, {1, 0, 0.5}, {-0.5, 0.8, 0.5}, {-0.5, -0.8, 0.5}};
  const TriMesh book = doubleSided(v, {{0, 1, 2}, {0, 3, 1}, {0, 1, 4}}, rng);
  EXPECT_EQ(orientedTriangles(collapseDoubleSidedSolids(book, &rep)), orientedTriangles(book));
  EXPECT_EQ(rep.solids_collapsed, 0);
  EXPECT_EQ(rep.parts_kept_double_sided, 1);

  // A single-sided closed mesh has no twin: returned as it is.
  const TriMesh box = makeBox({0.1, 0.1, 0.1}, 0.05);
  EXPECT_EQ(orientedTriangles(collapseDoubleSidedSolids(box, &rep)), orientedTriangles(box));
  EXPECT_EQ(rep.solids_collapsed + rep.parts_kept_double_sided, 0);
}

TEST(MeshRepair, PartsOfOneMeshAreJudgedSeparately) {
  std::mt19937 rng(7);
  // A double-sided box, a double-sided open sheet and a single-sided cylinder in one mesh.
  const TriMesh box = makeBox({0.1, 0.1, 0.1}, 0.05);
  test::FoldGrid g = test::foldGrid(1.2, 3, /*face_outside=*/true);
  const TriMesh sheet = TriMesh::build("sheet", g.vertices, g.triangles, 1e-9);
  const TriMesh cyl = makeCylinder(0.03, 0.1, 8, 0.1);
  std::vector<Eigen::Vector3d> v = verticesOf(box);
  const int sheet_offset = static_cast<int>(v.size());
  for (const auto& p : verticesOf(sheet)) v.push_back(p + Eigen::Vector3d(1, 0, 0));
  const int cyl_offset = static_cast<int>(v.size());
  for (const auto& p : verticesOf(cyl)) v.push_back(p + Eigen::Vector3d(0, 1, 0));
  std::vector<Eigen::Vector3i> t = trianglesOf(box);
  for (const auto& tri : trianglesOf(sheet, sheet_offset)) t.push_back(tri);
  const std::size_t n_twinned = t.size();
  for (std::size_t i = 0; i < n_twinned; ++i) t.emplace_back(t[i][0], t[i][2], t[i][1]);
  for (const auto& tri : trianglesOf(cyl, cyl_offset)) t.push_back(tri);
  std::shuffle(t.begin(), t.end(), rng);
  const TriMesh mixed = TriMesh::build("mixed", v, t);
  DoubleSidedRepair rep;
  const TriMesh out = collapseDoubleSidedSolids(mixed, &rep);
  EXPECT_EQ(rep.solids_collapsed, 1);
  EXPECT_EQ(rep.parts_kept_double_sided, 1);
  EXPECT_EQ(rep.triangles_removed, box.numTriangles());
  std::multiset<Tri> expected = orientedTriangles(mixed);
  for (const auto& tri : trianglesOf(box)) expected.erase(expected.find(canonical({tri[0], tri[2], tri[1]})));
  EXPECT_EQ(orientedTriangles(out), expected);
}

TEST(MeshRepair, SmallCracksAreToleratedLargeHolesAreNot) {
  std::mt19937 rng(8);
  const TriMesh box = makeBox({0.1, 0.1, 0.1}, 0.01);  // 1,200 small triangles
  std::vector<Eigen::Vector3i> cracked = trianglesOf(box);
  cracked.erase(cracked.begin() + 17);  // one missing triangle: a crack with three rim edges
  const TriMesh crack_box = TriMesh::build("cracked", verticesOf(box), cracked);
  DoubleSidedRepair rep;
  const TriMesh out = collapseDoubleSidedSolids(doubleSided(verticesOf(box), cracked, rng), &rep);
  EXPECT_EQ(rep.solids_collapsed, 1);
  EXPECT_EQ(rep.solids_with_holes, 1);
  EXPECT_EQ(rep.hole_rim_edges, 3);
  EXPECT_EQ(orientedTriangles(out), orientedTriangles(crack_box));

  // Half the box gone: an open tray; which side is outside is not decidable, both stay.
  std::vector<Eigen::Vector3i> tray;
  for (const auto& t : trianglesOf(box)) {
    const Eigen::Vector3d c = (box.vertex(t[0]) + box.vertex(t[1]) + box.vertex(t[2])) / 3.0;
    if (c.z() < 0.049) tray.push_back(t);
  }
  const TriMesh tray2 = doubleSided(verticesOf(box), tray, rng);
  EXPECT_EQ(orientedTriangles(collapseDoubleSidedSolids(tray2, &rep)), orientedTriangles(tray2));
  EXPECT_EQ(rep.parts_kept_double_sided, 1);
}

TEST(MeshRepair, TheSurfaceDoesNotChange) {
  std::mt19937 rng(9);
  const TriMesh solid = makeCapsule({0, 0, 0}, {0.1, 0.05, 0.2}, 0.05, 8, 2);
  const TriMesh twice = doubleSided(verticesOf(solid), trianglesOf(solid), rng);
  const TriMesh once = collapseDoubleSidedSolids(twice);
  std::uniform_real_distribution<double> u(-0.2, 0.4);
  for (int k = 0; k < 200; ++k) {
    const Eigen::Vector3d p(u(rng), u(rng), u(rng));
    EXPECT_DOUBLE_EQ(surfaceDistance(once, p), surfaceDistance(twice, p));
  }
}

TEST(MeshRepair, DrcFilesKeepTheirOutwardCopy) {
  const std::filesystem::path dir = FULLARM_SCENE_MESH_DIR;
  const std::filesystem::path wall = dir / "drc_practice_valve_wall" / "five_dice_wall.dae";
  const std::filesystem::path wheel = dir / "drc_practice_wheel_valve" / "valve_wheel.dae";
  MeshImportOptions keep;
  keep.collapse_double_sided_solids = false;
  // The wall: a 1.2192 x 2.4384 m plywood sheet, 9.5 mm thick (the model's documentation), with
  // bolt holes: its kept copy encloses that volume, less the holes.
  const TriMesh wall_as_is = importMesh(wall, keep);
  DoubleSidedRepair rep;
  const TriMesh wall_once = collapseDoubleSidedSolids(wall_as_is, &rep);
  EXPECT_EQ(wall_as_is.numTriangles(), 3280);
  EXPECT_EQ(wall_once.numTriangles(), 1640);
  EXPECT_EQ(rep.solids_collapsed, 1);
  EXPECT_EQ(wall_once.nonManifoldEdgeCount(), 0);
  EXPECT_EQ(wall_once.boundaryEdgeCount(), 0);
  const double sheet = 1.2192 * 2.4384 * 0.009525;
  EXPECT_GT(enclosedVolume(wall_once), 0.97 * sheet);
  EXPECT_LT(enclosedVolume(wall_once), 1.0 * sheet);
  EXPECT_EQ(importMesh(wall).numTriangles(), 1640) << "importMesh collapses by default";
  // The wheel: one solid with 26 crack edges.
  const TriMesh wheel_as_is = importMesh(wheel, keep);
  const TriMesh wheel_once = collapseDoubleSidedSolids(wheel_as_is, &rep);
  EXPECT_EQ(wheel_as_is.numTriangles(), 10992);
  EXPECT_EQ(wheel_once.numTriangles(), 5496);
  EXPECT_EQ(rep.solids_with_holes, 1);
  EXPECT_EQ(wheel_once.boundaryEdgeCount(), rep.hole_rim_edges);
  EXPECT_GT(enclosedVolume(wheel_once), 0.0);
}
}  // namespace
}  // namespace fullarm::haptics
