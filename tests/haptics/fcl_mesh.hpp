#pragma once
/// @file
/// The FCL peer's view of a fullarm mesh or link capsule, shared by the haptics tests (FCL as the distance
/// oracle) and bench/haptics_local_bench.cpp (FCL as the timed peer). FCL is never linked into
/// fullarm::haptics; only targets that link `fcl` include this header.

#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/geometry/shape/capsule.h>
#include <fcl/geometry/shape/sphere.h>
#include <fcl/math/bv/OBBRSS.h>

#include <cstddef>
#include <memory>
#include <vector>

#include "fullarm/haptics/primitives.hpp"
#include "fullarm/haptics/snch.hpp"

namespace fullarm::haptics::test {

/// An FCL OBBRSS bounding-volume hierarchy over the vertices and triangles of `mesh` (mesh
/// frame, metres), ready to be placed with an fcl::CollisionObjectd.
inline std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>> fclModel(const TriMesh& mesh) {
  auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
  std::vector<fcl::Vector3d> v;
  std::vector<fcl::Triangle> t;
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(mesh.vertex(i));
  for (int i = 0; i < mesh.numTriangles(); ++i) {
    t.emplace_back(static_cast<std::size_t>(mesh.triangle(i)[0]), static_cast<std::size_t>(mesh.triangle(i)[1]),
                   static_cast<std::size_t>(mesh.triangle(i)[2]));
  }
  model->beginModel();
  model->addSubModel(v, t);
  model->endModel();
  return model;
}

/// FCL's shape of a link capsule and its pose in the link frame: fcl::Capsuled runs along its
/// z axis, centred (a sphere when the segment has zero length).
struct FclCapsule {
  std::shared_ptr<fcl::CollisionGeometryd> shape;
  Eigen::Isometry3d X_LC = Eigen::Isometry3d::Identity();
};

inline FclCapsule fclCapsule(const Capsule& c) {
  FclCapsule out;
  const Eigen::Vector3d axis = c.b_m - c.a_m;
  out.X_LC.translation() = 0.5 * (c.a_m + c.b_m);
  if (axis.norm() > 0.0) {
    out.X_LC.linear() = Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), axis).toRotationMatrix();
    out.shape = std::make_shared<fcl::Capsuled>(c.radius_m, axis.norm());
  } else {
    out.shape = std::make_shared<fcl::Sphered>(c.radius_m);
  }
  return out;
}

}  // namespace fullarm::haptics::test
