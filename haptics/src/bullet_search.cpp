#include "fullarm/haptics/bullet_search.hpp"

#include <BulletCollision/CollisionShapes/btTriangleShape.h>
#include <btBulletCollisionCommon.h>

#include <algorithm>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "fullarm/haptics/snch.hpp"

namespace fullarm::haptics {
namespace {

btTransform toBullet(const Eigen::Isometry3d& X) {
  const Eigen::Matrix3d& R = X.linear();
  const btMatrix3x3 basis(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0), R(2, 1), R(2, 2));
  return btTransform(basis, btVector3(X.translation().x(), X.translation().y(), X.translation().z()));
}

btVector3 toBullet(const Eigen::Vector3d& v) {
  return btVector3(v.x(), v.y(), v.z());
}
Eigen::Vector3d toEigen(const btVector3& v) {
  return Eigen::Vector3d(v.x(), v.y(), v.z());
}

// Every vertex on the inner side of every face plane (and no boundary): a convex solid.
bool isConvexSolid(const TriMesh& mesh) {
  if (mesh.boundaryEdgeCount() != 0 || mesh.nonManifoldEdgeCount() != 0) return false;
  Eigen::Vector3d lo = mesh.vertex(0);
  Eigen::Vector3d hi = lo;
  for (int v = 1; v < mesh.numVertices(); ++v) {
    lo = lo.cwiseMin(mesh.vertex(v));
    hi = hi.cwiseMax(mesh.vertex(v));
  }
  const double tolerance = 1e-9 * (hi - lo).norm();
  for (int t = 0; t < mesh.numTriangles(); ++t) {
    const Eigen::Vector3d& n = mesh.faceNormal(t);
    const double offset = n.dot(mesh.vertex(mesh.triangle(t)[0]));
    for (int v = 0; v < mesh.numVertices(); ++v) {
      if (n.dot(mesh.vertex(v)) - offset > tolerance) return false;
    }
  }
  return true;
}

std::unique_ptr<btConvexHullShape> convexHull(const TriMesh& mesh) {
  auto hull = std::make_unique<btConvexHullShape>();
  for (int v = 0; v < mesh.numVertices(); ++v) hull->addPoint(toBullet(mesh.vertex(v)), false);
  hull->recalcLocalAabb();
  hull->setMargin(0.0);
  return hull;
}

// Collects one entry per reported (link triangle, object triangle) pair.
struct PairCollector : btCollisionWorld::ContactResultCallback {
  const btCollisionObject* link_object = nullptr;
  bool capsule = false;  // the link is one convex shape: no link triangle
  std::vector<TrianglePairPoints>* out = nullptr;

  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int /*part0*/, int index0,
                           const btCollisionObjectWrapper* w1, int /*part1*/, int index1) override {
    const bool link_is_a = w0->getCollisionObject() == link_object;
    (void)w1;
    TrianglePairPoints r;
    r.tri_link = capsule ? -1 : (link_is_a ? index0 : index1);
    r.tri_object = link_is_a ? index1 : index0;
    const Eigen::Vector3d a = toEigen(cp.getPositionWorldOnA());
    const Eigen::Vector3d b = toEigen(cp.getPositionWorldOnB());
    r.p_W = link_is_a ? a : b;
    r.q_W = link_is_a ? b : a;
    r.distance_m = cp.getDistance();
    out->push_back(r);
    return 0;
  }
};

// Collects the indices of the triangles Bullet's BVH reports.
struct TriangleIndexCollector : btTriangleCallback {
  std::vector<int>* out = nullptr;
  void processTriangle(btVector3* /*triangle*/, int /*part*/, int index) override { out->push_back(index); }
};

// Deepest reported penetration (negative distance) of a convex-shape pair query.
struct DeepestCollector : btCollisionWorld::ContactResultCallback {
  const btCollisionObject* link_object = nullptr;
  LinkPenetration result;

  btScalar addSingleResult(btManifoldPoint& cp, const btCollisionObjectWrapper* w0, int, int,
                           const btCollisionObjectWrapper*, int, int) override {
    const double depth = -cp.getDistance();
    if (depth > result.depth_m) {
      const bool link_is_a = w0->getCollisionObject() == link_object;
      result.penetrating = true;
      result.depth_m = depth;
      const Eigen::Vector3d a = toEigen(cp.getPositionWorldOnA());
      const Eigen::Vector3d b = toEigen(cp.getPositionWorldOnB());
      result.p_W = link_is_a ? a : b;
      result.q_W = link_is_a ? b : a;
    }
    return 0;
  }
};

}  // namespace

struct BulletGlobalSearch::Impl {
  struct LinkShape {
    int num_triangles = 0;
    std::vector<std::unique_ptr<btTriangleShape>> triangles;
    std::unique_ptr<btCompoundShape> compound;
    bool capsule = false;                                    // the exact capsule (no triangles)
    double radius_m = 0.0;                                   // capsule only
    double length_m = 0.0;                                   // capsule only: its segment's length
    std::unique_ptr<btConvexShape> convex;                   // the capsule, or the mesh's hull
    Eigen::Isometry3d X_LC = Eigen::Isometry3d::Identity();  // pose of `convex` in the link frame
    btCollisionObject mesh_object;
    btCollisionObject convex_object;
  };
  struct ObjectShape {
    int num_triangles = 0;
    std::vector<btScalar> vertices;
    std::vector<int> indices;
    std::unique_ptr<btTriangleIndexVertexArray> array;
    std::unique_ptr<btBvhTriangleMeshShape> shape;
    std::unique_ptr<btConvexHullShape> hull;  // convex objects only
    btCollisionObject mesh_object;
    btCollisionObject hull_object;
  };

  btDefaultCollisionConfiguration config;
  btCollisionDispatcher dispatcher{&config};
  btDbvtBroadphase broadphase;
  btCollisionWorld world{&dispatcher, &broadphase, &config};
  std::vector<std::unique_ptr<LinkShape>> links;
  std::vector<std::unique_ptr<ObjectShape>> objects;

  void addLink(const CollisionWorld& cw, int l) {
    if (!cw.hasLinkGeometry(l)) {
      links.push_back(nullptr);
      return;
    }
    auto link = std::make_unique<LinkShape>();
    if (cw.linkShape(l) == fullarm::haptics::LinkShape::kCapsule) {
      // The exact capsule: Bullet's GJK runs on its core segment with the radius as margin.
      const Capsule& c = cw.linkCapsule(l);
      const double length = (c.b_m - c.a_m).norm();
      if (length > 0.0) {
        // btCapsuleShape runs along its y axis, centred; the capsule's core segment is its height.
        link->convex = std::make_unique<btCapsuleShape>(c.radius_m, length);
        link->X_LC.linear() =
            Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitY(), c.b_m - c.a_m).toRotationMatrix();
      } else {
        link->convex = std::make_unique<btSphereShape>(c.radius_m);
      }
      link->X_LC.translation() = 0.5 * (c.a_m + c.b_m);
      link->capsule = true;
      link->radius_m = c.radius_m;
      link->length_m = length;
    } else {
      const TriMesh& mesh = cw.linkMesh(l);
      link->num_triangles = mesh.numTriangles();
      link->compound = std::make_unique<btCompoundShape>(true, mesh.numTriangles());
      for (int t = 0; t < mesh.numTriangles(); ++t) {
        const Eigen::Vector3i& tri = mesh.triangle(t);
        auto shape = std::make_unique<btTriangleShape>(toBullet(mesh.vertex(tri[0])), toBullet(mesh.vertex(tri[1])),
                                                       toBullet(mesh.vertex(tri[2])));
        shape->setMargin(0.0);  // exact distances: no rounded skin around the triangle
        link->compound->addChildShape(btTransform::getIdentity(), shape.get());
        link->triangles.push_back(std::move(shape));
      }
      link->compound->setMargin(0.0);
      link->mesh_object.setCollisionShape(link->compound.get());
      link->convex = convexHull(mesh);
    }
    link->convex_object.setCollisionShape(link->convex.get());
    links.push_back(std::move(link));
  }

  void addObject(const TriMesh& mesh) {
    auto object = std::make_unique<ObjectShape>();
    object->num_triangles = mesh.numTriangles();
    object->vertices.reserve(3 * static_cast<std::size_t>(mesh.numVertices()));
    for (int v = 0; v < mesh.numVertices(); ++v) {
      for (int k = 0; k < 3; ++k) object->vertices.push_back(mesh.vertex(v)[k]);
    }
    object->indices.reserve(3 * static_cast<std::size_t>(mesh.numTriangles()));
    for (int t = 0; t < mesh.numTriangles(); ++t) {
      for (int k = 0; k < 3; ++k) object->indices.push_back(mesh.triangle(t)[k]);
    }
    object->array = std::make_unique<btTriangleIndexVertexArray>(
        mesh.numTriangles(), object->indices.data(), static_cast<int>(3 * sizeof(int)), mesh.numVertices(),
        object->vertices.data(), static_cast<int>(3 * sizeof(btScalar)));
    object->shape = std::make_unique<btBvhTriangleMeshShape>(object->array.get(), true, true);
    object->shape->setMargin(0.0);
    object->mesh_object.setCollisionShape(object->shape.get());
    if (isConvexSolid(mesh)) {
      object->hull = convexHull(mesh);
      object->hull_object.setCollisionShape(object->hull.get());
    }
    objects.push_back(std::move(object));
  }
};

BulletGlobalSearch::BulletGlobalSearch(const CollisionWorld& world) : impl_(std::make_unique<Impl>()) {
  bool any_link = false;
  for (int l = 0; l < world.numLinks(); ++l) {
    impl_->addLink(world, l);
    any_link = any_link || world.hasLinkGeometry(l);
  }
  if (!any_link) throw std::invalid_argument("BulletGlobalSearch: the collision world has no link geometry");
  for (int o = 0; o < world.numObjects(); ++o) impl_->addObject(world.object(o).mesh);
}

BulletGlobalSearch::~BulletGlobalSearch() = default;

void BulletGlobalSearch::closestTrianglePairs(int link, const Eigen::Isometry3d& X_WL, int object,
                                              const Eigen::Isometry3d& X_WO, double cutoff_m,
                                              std::vector<TrianglePairPoints>& out) {
  Impl::LinkShape& l = *impl_->links.at(static_cast<std::size_t>(link));
  Impl::ObjectShape& o = *impl_->objects.at(static_cast<std::size_t>(object));
  btCollisionObject& link_object = l.capsule ? l.convex_object : l.mesh_object;
  link_object.setWorldTransform(toBullet(l.capsule ? X_WL * l.X_LC : X_WL));
  o.mesh_object.setWorldTransform(toBullet(X_WO));
  const std::size_t begin = out.size();
  PairCollector collector;
  collector.link_object = &link_object;
  collector.capsule = l.capsule;
  collector.out = &out;
  collector.m_closestDistanceThreshold = cutoff_m;
  impl_->world.contactPairTest(&link_object, &o.mesh_object, collector);
  // One entry per triangle pair (the closest, should Bullet report a pair twice), within L.
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(begin), out.end(),
            [](const TrianglePairPoints& a, const TrianglePairPoints& b) {
              return std::tie(a.tri_link, a.tri_object, a.distance_m) <
                     std::tie(b.tri_link, b.tri_object, b.distance_m);
            });
  const auto last = std::unique(out.begin() + static_cast<std::ptrdiff_t>(begin), out.end(),
                                [](const TrianglePairPoints& a, const TrianglePairPoints& b) {
                                  return a.tri_link == b.tri_link && a.tri_object == b.tri_object;
                                });
  out.erase(std::remove_if(out.begin() + static_cast<std::ptrdiff_t>(begin), last,
                           [cutoff_m](const TrianglePairPoints& p) { return p.distance_m > cutoff_m; }),
            out.end());
}

void BulletGlobalSearch::capsuleCandidateTriangles(int link, const Eigen::Isometry3d& X_WL, int object,
                                                   const Eigen::Isometry3d& X_WO, double cutoff_m,
                                                   std::vector<int>& out) const {
  const Impl::LinkShape& l = *impl_->links.at(static_cast<std::size_t>(link));
  const Impl::ObjectShape& o = *impl_->objects.at(static_cast<std::size_t>(object));
  if (!l.capsule) throw std::invalid_argument("capsuleCandidateTriangles: link " + std::to_string(link) + " is not a capsule");
  // The capsule's box in the object frame (where Bullet holds the object's vertices), grown by
  // the radius and the cutoff.
  const Eigen::Isometry3d X_OC = X_WO.inverse() * X_WL * l.X_LC;
  const Eigen::Vector3d half_axis = X_OC.linear() * Eigen::Vector3d(0.0, 0.5 * l.length_m, 0.0);
  const Eigen::Vector3d grow = Eigen::Vector3d::Constant(l.radius_m + cutoff_m);
  const Eigen::Vector3d lo = X_OC.translation() - half_axis.cwiseAbs() - grow;
  const Eigen::Vector3d hi = X_OC.translation() + half_axis.cwiseAbs() + grow;
  const std::size_t begin = out.size();
  TriangleIndexCollector collector;
  collector.out = &out;
  o.shape->processAllTriangles(&collector, toBullet(lo), toBullet(hi));
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(begin), out.end());
  out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(begin), out.end()), out.end());
}

void BulletGlobalSearch::search(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m,
                                double prune_radius_m, std::vector<LocalMinimum>& out) {
  if (world.numLinks() != static_cast<int>(impl_->links.size()) ||
      world.numObjects() != static_cast<int>(impl_->objects.size())) {
    throw std::invalid_argument("BulletGlobalSearch::search: not the collision world the search was built for");
  }
  out.clear();
  last_pairs_ = 0;
  for (int l = 0; l < world.numLinks(); ++l) {
    if (!world.hasLinkGeometry(l)) continue;
    const Impl::LinkShape* shape = impl_->links[static_cast<std::size_t>(l)].get();
    const bool capsule = world.linkShape(l) == LinkShape::kCapsule;
    if (shape == nullptr || shape->capsule != capsule ||
        (!capsule && shape->num_triangles != world.linkMesh(l).numTriangles())) {
      throw std::invalid_argument("BulletGlobalSearch::search: link geometry changed since the search was built");
    }
    const Eigen::Isometry3d& X_WL = fk.X_WL[static_cast<std::size_t>(l)];
    for (int o = 0; o < world.numObjects(); ++o) {
      const CollisionObject& obj = world.object(o);
      const Eigen::Isometry3d X_OL = obj.X_WO.inverse() * X_WL;
      const std::size_t begin = out.size();
      LocalMinimum m;
      if (capsule) {
        // Bullet's BVH picks the candidates; every one gets the exact test.
        triangles_.clear();
        capsuleCandidateTriangles(l, X_WL, o, obj.X_WO, cutoff_m, triangles_);
        last_pairs_ += static_cast<long>(triangles_.size());
        const Capsule& c = world.linkCapsule(l);
        const Eigen::Vector3d a = X_OL * c.a_m;
        const Eigen::Vector3d b = X_OL * c.b_m;
        const Eigen::Isometry3d X_LO = X_OL.inverse();
        for (const int t : triangles_) {
          if (evaluateCapsuleTriangle(a, b, c.radius_m, X_LO, obj.mesh, t, cutoff_m, m)) {
            m.link = l;
            m.object = o;
            m.u_W = obj.X_WO.linear() * m.u_W;
            out.push_back(m);
          }
        }
      } else {
        pairs_.clear();
        closestTrianglePairs(l, X_WL, o, obj.X_WO, cutoff_m, pairs_);
        last_pairs_ += static_cast<long>(pairs_.size());
        for (const TrianglePairPoints& pair : pairs_) {
          if (evaluateTrianglePair(world.linkMesh(l), pair.tri_link, obj.mesh, pair.tri_object, X_OL, cutoff_m, m)) {
            m.link = l;
            m.object = o;
            m.u_W = obj.X_WO.linear() * m.u_W;
            out.push_back(m);
          }
        }
      }
      mergeDuplicateMinima(out, begin);
    }
  }
  pruneMinima(out, prune_radius_m);
}

LinkPenetration BulletGlobalSearch::penetration(int link, const Eigen::Isometry3d& X_WL, int object,
                                                const Eigen::Isometry3d& X_WO) {
  Impl::LinkShape& l = *impl_->links.at(static_cast<std::size_t>(link));
  Impl::ObjectShape& o = *impl_->objects.at(static_cast<std::size_t>(object));
  l.convex_object.setWorldTransform(toBullet(X_WL * l.X_LC));
  DeepestCollector collector;
  collector.link_object = &l.convex_object;
  collector.m_closestDistanceThreshold = 0.0;
  btCollisionObject& target = o.hull ? o.hull_object : o.mesh_object;
  target.setWorldTransform(toBullet(X_WO));
  impl_->world.contactPairTest(&l.convex_object, &target, collector);
  collector.result.solid_object = o.hull != nullptr;
  return collector.result;
}

}  // namespace fullarm::haptics
