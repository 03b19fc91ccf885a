#pragma once
// Shared helpers of the haptics tests: the brute-force local-minimum oracle, random small
// meshes and random poses.

#include <Eigen/Geometry>
#include <cmath>
#include <random>
#include <utility>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/minima.hpp"
#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/snch.hpp"

namespace fullarm::haptics::test {

/// Every local minimum within cutoff by testing ALL triangle pairs (no hierarchy, no cones),
/// merged by feature pair. u_W in the world frame.
inline std::vector<LocalMinimum> bruteForceMinima(const TriMesh& link_mesh, const Eigen::Isometry3d& X_WL,
                                                  const TriMesh& obj_mesh, const Eigen::Isometry3d& X_WO,
                                                  double cutoff_m) {
  std::vector<LocalMinimum> out;
  const Eigen::Isometry3d X_OL = X_WO.inverse() * X_WL;
  LocalMinimum m;
  for (int a = 0; a < link_mesh.numTriangles(); ++a) {
    for (int b = 0; b < obj_mesh.numTriangles(); ++b) {
      if (evaluateTrianglePair(link_mesh, a, obj_mesh, b, X_OL, cutoff_m, m)) {
        m.u_W = X_WO.linear() * m.u_W;
        out.push_back(m);
      }
    }
  }
  mergeDuplicateMinima(out, 0);
  return out;
}

/// Every local minimum within cutoff between a capsule and a mesh by testing ALL triangles
/// (evaluateCapsuleTriangle on each, no hierarchy, no cones), merged by feature pair. u_W in
/// the world frame.
inline std::vector<LocalMinimum> bruteForceCapsuleMinima(const Capsule& capsule, const Eigen::Isometry3d& X_WL,
                                                         const TriMesh& obj_mesh, const Eigen::Isometry3d& X_WO,
                                                         double cutoff_m) {
  std::vector<LocalMinimum> out;
  const Eigen::Isometry3d X_OL = X_WO.inverse() * X_WL;
  const Eigen::Vector3d a = X_OL * capsule.a_m;
  const Eigen::Vector3d b = X_OL * capsule.b_m;
  LocalMinimum m;
  for (int t = 0; t < obj_mesh.numTriangles(); ++t) {
    if (evaluateCapsuleTriangle(a, b, capsule.radius_m, X_OL.inverse(), obj_mesh, t, cutoff_m, m)) {
      m.u_W = X_WO.linear() * m.u_W;
      out.push_back(m);
    }
  }
  mergeDuplicateMinima(out, 0);
  return out;
}

/// The brute-force minima of every link with geometry (capsule or mesh) against every object
/// of `world` at the link frames of `fk`, link/object set, in (link, object) order.
inline std::vector<LocalMinimum> bruteForceWorldMinima(const CollisionWorld& world, const arm::ArmData& fk,
                                                       double cutoff_m) {
  std::vector<LocalMinimum> all;
  for (int l = 0; l < world.numLinks(); ++l) {
    if (!world.hasLinkGeometry(l)) continue;
    const Eigen::Isometry3d& X_WL = fk.X_WL[static_cast<std::size_t>(l)];
    for (int o = 0; o < world.numObjects(); ++o) {
      const CollisionObject& obj = world.object(o);
      std::vector<LocalMinimum> pair =
          world.linkShape(l) == LinkShape::kCapsule
              ? bruteForceCapsuleMinima(world.linkCapsule(l), X_WL, obj.mesh, obj.X_WO, cutoff_m)
              : bruteForceMinima(world.linkMesh(l), X_WL, obj.mesh, obj.X_WO, cutoff_m);
      for (LocalMinimum& m : pair) {
        m.link = l;
        m.object = o;
      }
      all.insert(all.end(), pair.begin(), pair.end());
    }
  }
  return all;
}

/// Replaces every capsule link of `world` by its faceted mesh (makeLinkCapsuleMesh: `segments`
/// around the axis, `rings` per hemisphere), so the world's queries run the mesh-link path.
/// Returns the number of links replaced.
inline int facetCapsuleLinks(CollisionWorld& world, int segments, int rings) {
  int n = 0;
  for (int l = 0; l < world.numLinks(); ++l) {
    if (world.linkShape(l) != LinkShape::kCapsule) continue;
    world.setLinkMesh(l, makeLinkCapsuleMesh(world.model(), l, segments, rings));
    ++n;
  }
  return n;
}

/// Minimum over all triangle pairs of the triangle-triangle distance (plain global minimum).
inline double bruteForceDistance(const TriMesh& a, const Eigen::Isometry3d& X_WA, const TriMesh& b,
                                 const Eigen::Isometry3d& X_WB) {
  const Eigen::Isometry3d X_BA = X_WB.inverse() * X_WA;
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < a.numTriangles(); ++i) {
    for (int j = 0; j < b.numTriangles(); ++j) {
      best = std::min(best, closestPointsInObjectFrame(a, i, b, j, X_BA).distance_m);
    }
  }
  return best;
}

inline Eigen::Isometry3d randomPose(std::mt19937& rng, double translation_scale) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  std::uniform_real_distribution<double> u(-translation_scale, translation_scale);
  Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
  X.linear() = q.toRotationMatrix();
  X.translation() = Eigen::Vector3d(u(rng), u(rng), u(rng));
  return X;
}

/// A random small closed mesh (box, capsule, cylinder, I-beam or frame), 12..~200 triangles,
/// about 0.1-0.3 m across (small enough for brute force over all triangle pairs).
inline TriMesh randomSmallMesh(std::mt19937& rng) {
  std::uniform_real_distribution<double> size(0.05, 0.25);
  std::uniform_int_distribution<int> kind(0, 4);
  switch (kind(rng)) {
    case 0:
      return makeBox({size(rng), size(rng), size(rng)}, std::uniform_real_distribution<double>(0.07, 0.3)(rng));
    case 1:
      return makeCapsule({0, 0, 0}, {0, 0, size(rng)}, 0.3 * size(rng), std::uniform_int_distribution<int>(5, 10)(rng),
                         std::uniform_int_distribution<int>(1, 2)(rng));
    case 2:
      return makeCylinder(0.5 * size(rng), size(rng), std::uniform_int_distribution<int>(5, 10)(rng), 0.1);
    case 3:
      return makeIBeam(0.12, 0.08, 0.015, 0.01, size(rng), 0.1);
    default:
      return makeRectangularFrame(0.2, 0.16, 0.04, 0.03, 0.08);
  }
}

/// Vertices and triangles of an open sheet: two 0.1 x 0.1 m panels of n x n squares (two
/// triangles each) meeting along the x axis (j = 0, duplicated: weld when building) at `fold`
/// radians between the panels. Panel 1 is wound the other way when `face_outside`, so that both
/// panels face the outside of the fold; otherwise both are wound alike.
struct FoldGrid {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<Eigen::Vector3i> triangles;
};
inline FoldGrid foldGrid(double fold, int n, bool face_outside) {
  FoldGrid g;
  for (int panel = 0; panel < 2; ++panel) {
    for (int i = 0; i <= n; ++i) {
      for (int j = 0; j <= n; ++j) {
        const double x = 0.1 * i / n;
        const double r = 0.1 * j / n;
        g.vertices.emplace_back(x, panel == 0 ? r : r * std::cos(fold), panel == 0 ? 0.0 : r * std::sin(fold));
      }
    }
  }
  auto id = [n](int panel, int i, int j) { return panel * (n + 1) * (n + 1) + i * (n + 1) + j; };
  for (int panel = 0; panel < 2; ++panel) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        Eigen::Vector3i a(id(panel, i, j), id(panel, i + 1, j), id(panel, i + 1, j + 1));
        Eigen::Vector3i b(id(panel, i, j), id(panel, i + 1, j + 1), id(panel, i, j + 1));
        if (face_outside && panel == 1) {
          std::swap(a[1], a[2]);
          std::swap(b[1], b[2]);
        }
        g.triangles.push_back(a);
        g.triangles.push_back(b);
      }
    }
  }
  return g;
}

}  // namespace fullarm::haptics::test
