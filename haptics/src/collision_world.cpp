#include "fullarm/haptics/collision_world.hpp"

namespace fullarm::haptics {

CollisionWorld::CollisionWorld(const arm::ArmModel& model) : CollisionWorld(model, Options{}) {}

CollisionWorld::CollisionWorld(const arm::ArmModel& model, const Options& /*options*/) : model_(&model) {
  links_.resize(static_cast<std::size_t>(model.numJoints()));
  for (int l = 0; l < model.numJoints(); ++l) {
    const arm::LinkGeometry& g = model.joints[static_cast<std::size_t>(l)].geometry;
    if (g.type != arm::LinkGeometry::Type::kCapsule) continue;
    Link& link = links_[static_cast<std::size_t>(l)];
    link.shape = LinkShape::kCapsule;
    link.capsule = {g.from_m, g.to_m, g.radius_m};
  }
}

void CollisionWorld::setLinkMesh(int link, const TriMesh& mesh, const Eigen::Isometry3d& X_LM) {
  if (link < 0 || link >= numLinks()) {
    throw MeshError(mesh.source(), "setLinkMesh: link index " + std::to_string(link) + " out of range [0, " +
                                       std::to_string(numLinks()) + ")");
  }
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  v.reserve(static_cast<std::size_t>(mesh.numVertices()));
  t.reserve(static_cast<std::size_t>(mesh.numTriangles()));
  for (int i = 0; i < mesh.numVertices(); ++i) v.push_back(X_LM * mesh.vertex(i));
  for (int i = 0; i < mesh.numTriangles(); ++i) t.push_back(mesh.triangle(i));
  auto lm = std::make_shared<LinkMesh>();
  lm->mesh = TriMesh::build(mesh.source(), std::move(v), std::move(t));
  lm->tree = buildSnchTree(lm->mesh);
  lm->cones = computeNeighbourCones(lm->mesh);
  Link& entry = links_[static_cast<std::size_t>(link)];
  entry.shape = LinkShape::kMesh;
  entry.mesh = std::move(lm);
}

int CollisionWorld::addObject(std::string name, TriMesh mesh, const Eigen::Isometry3d& X_WO) {
  CollisionObject o;
  o.name = std::move(name);
  o.tree = buildSnchTree(mesh);
  o.cones = computeNeighbourCones(mesh);
  o.mesh = std::move(mesh);
  o.X_WO = X_WO;
  objects_.push_back(std::move(o));
  return numObjects() - 1;
}

void CollisionWorld::setObjectPose(int object, const Eigen::Isometry3d& X_WO) {
  objects_[static_cast<std::size_t>(object)].X_WO = X_WO;
}

int CollisionWorld::objectIndex(std::string_view name) const noexcept {
  for (int i = 0; i < numObjects(); ++i) {
    if (objects_[static_cast<std::size_t>(i)].name == name) return i;
  }
  return -1;
}

void SnchGlobalSearch::search(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m,
                              double prune_radius_m, std::vector<LocalMinimum>& out) {
  out.clear();
  stats_ = {};
  SnchQueryStats pair_stats;
  for (int l = 0; l < world.numLinks(); ++l) {
    const LinkShape shape = world.linkShape(l);
    if (shape == LinkShape::kNone) continue;
    const Eigen::Isometry3d& X_WL = fk.X_WL[static_cast<std::size_t>(l)];
    for (int o = 0; o < world.numObjects(); ++o) {
      const CollisionObject& obj = world.object(o);
      const std::size_t begin = out.size();
      if (shape == LinkShape::kCapsule) {
        querySnchCapsule(world.linkCapsule(l), X_WL, obj.tree, obj.mesh, obj.X_WO, cutoff_m, scratch_, out,
                         &pair_stats);
      } else {
        querySnchPair(world.linkTree(l), world.linkMesh(l), X_WL, obj.tree, obj.mesh, obj.X_WO, cutoff_m, scratch_, out,
                      &pair_stats);
      }
      for (std::size_t i = begin; i < out.size(); ++i) {
        out[i].link = l;
        out[i].object = o;
      }
      stats_.node_pairs_visited += pair_stats.node_pairs_visited;
      stats_.pruned_by_distance += pair_stats.pruned_by_distance;
      stats_.pruned_by_cone += pair_stats.pruned_by_cone;
      stats_.pruned_by_convex_bound += pair_stats.pruned_by_convex_bound;
      stats_.convex_hull_tests += pair_stats.convex_hull_tests;
      stats_.triangle_pairs_tested += pair_stats.triangle_pairs_tested;
    }
  }
  pruneMinima(out, prune_radius_m);
}

void CollisionWorld::globalSearch(const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
                                  std::vector<LocalMinimum>& out) const {
  SnchGlobalSearch search;
  search.search(*this, fk, cutoff_m, prune_radius_m, out);
}

void globalSearch(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m, double prune_radius_m,
                  std::vector<LocalMinimum>& out) {
  SnchGlobalSearch search;
  search.search(world, fk, cutoff_m, prune_radius_m, out);
}

}  // namespace fullarm::haptics
