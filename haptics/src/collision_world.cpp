#include "fullarm/haptics/collision_world.hpp"

#include "fullarm/haptics/hierarchy_cache.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <exception>
#include <mutex>
#include <numeric>
#include <stdexcept>
#include <thread>

namespace fullarm::haptics {

CollisionWorld::CollisionWorld(const arm::ArmModel& model) : CollisionWorld(model, Options{}) {}

CollisionWorld::CollisionWorld(const arm::ArmModel& model, const Options& options) : model_(&model), options_(options) {
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
  revision_.value = Revision::next();
}

int CollisionWorld::addObject(std::string name, TriMesh mesh, const Eigen::Isometry3d& X_WO) {
  CollisionObject o;
  o.name = std::move(name);
  MeshHierarchy h = options_.hierarchy_cache_dir.empty() ? buildMeshHierarchy(mesh)
                                                         : hierarchyFromCache(mesh, options_.hierarchy_cache_dir);
  o.tree = std::move(h.tree);
  o.cones = std::move(h.cones);
  o.mesh = std::move(mesh);
  o.X_WO = X_WO;
  objects_.push_back(std::move(o));
  revision_.value = Revision::next();
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

std::uint64_t CollisionWorld::Revision::next() noexcept {
  static std::atomic<std::uint64_t> counter{0};
  return counter.fetch_add(1, std::memory_order_relaxed) + 1;
}

// The search's per-pair state and its helper threads.
struct SnchGlobalSearch::Impl {
  struct Task {
    int link = -1;
    int object = -1;
    std::vector<LocalMinimum> out;  // this pair's minima, canonical order
    SnchQueryStats stats;
    CapsuleFront front;    // coherence (capsule links)
    double cost_ns = 0.0;  // the pair's time in the previous search
  };

  explicit Impl(int threads) : scratch(static_cast<std::size_t>(threads)) {
    for (int k = 1; k < threads; ++k) helpers.emplace_back([this, k] { helperLoop(k); });
  }
  ~Impl() {
    stop.store(true, std::memory_order_relaxed);
    generation.fetch_add(1, std::memory_order_release);
    generation.notify_all();
    for (std::thread& t : helpers) t.join();
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  // The tasks of `world` (every link with geometry x every object, link-major); kept (with
  // their fronts and costs) while the world's revision and the cutoff stay.
  void prepare(const CollisionWorld& w, double cutoff_m) {
    if (w.revision() == revision && cutoff_m == cutoff && !tasks.empty()) return;
    tasks.clear();
    for (int l = 0; l < w.numLinks(); ++l) {
      if (!w.hasLinkGeometry(l)) continue;
      for (int o = 0; o < w.numObjects(); ++o) {
        Task t;
        t.link = l;
        t.object = o;
        tasks.push_back(std::move(t));
      }
    }
    revision = w.revision();
    cutoff = cutoff_m;
    order.resize(tasks.size());
    std::iota(order.begin(), order.end(), 0);
  }

  void runTask(Task& t, SnchQueryScratch& s) {
    const auto start = std::chrono::steady_clock::now();
    const CollisionObject& obj = world->object(t.object);
    const Eigen::Isometry3d& X_WL = fk->X_WL[static_cast<std::size_t>(t.link)];
    t.out.clear();
    if (world->linkShape(t.link) == LinkShape::kCapsule) {
      if (coherent) {
        querySnchCapsuleCoherent(world->linkCapsule(t.link), X_WL, obj.tree, obj.mesh, obj.X_WO, cutoff, s, t.front,
                                 t.out, &t.stats);
      } else {
        querySnchCapsule(world->linkCapsule(t.link), X_WL, obj.tree, obj.mesh, obj.X_WO, cutoff, s, t.out, &t.stats);
      }
    } else {
      querySnchPair(world->linkTree(t.link), world->linkMesh(t.link), X_WL, obj.tree, obj.mesh, obj.X_WO, cutoff, s,
                    t.out, &t.stats);
    }
    for (LocalMinimum& m : t.out) {
      m.link = t.link;
      m.object = t.object;
    }
    t.cost_ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - start).count();
  }

  // Claims and runs tasks (in `order`) until none is left.
  void drain(int thread) noexcept {
    SnchQueryScratch& s = scratch[static_cast<std::size_t>(thread)];
    for (;;) {
      const std::size_t k = next.fetch_add(1, std::memory_order_relaxed);
      if (k >= order.size()) return;
      try {
        runTask(tasks[order[k]], s);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(error_mutex);
        if (!error) error = std::current_exception();
      }
    }
  }

  void helperLoop(int thread) noexcept {
    std::uint64_t seen = 0;
    for (;;) {
      generation.wait(seen, std::memory_order_acquire);
      seen = generation.load(std::memory_order_acquire);
      if (stop.load(std::memory_order_relaxed)) return;
      drain(thread);
      if (finished.fetch_add(1, std::memory_order_acq_rel) + 1 == static_cast<int>(helpers.size())) {
        finished.notify_one();
      }
    }
  }

  void runAll(const CollisionWorld& w, const arm::ArmData& k, bool coherent_pairs) {
    world = &w;
    fk = &k;
    coherent = coherent_pairs;
    // The costliest pairs first (longest processing time first), by the previous search.
    std::stable_sort(order.begin(), order.end(),
                     [this](std::size_t x, std::size_t y) { return tasks[x].cost_ns > tasks[y].cost_ns; });
    next.store(0, std::memory_order_relaxed);
    error = nullptr;
    if (!helpers.empty()) {
      finished.store(0, std::memory_order_relaxed);
      generation.fetch_add(1, std::memory_order_release);
      generation.notify_all();
    }
    drain(0);
    if (!helpers.empty()) {
      for (int done = finished.load(std::memory_order_acquire); done != static_cast<int>(helpers.size());
           done = finished.load(std::memory_order_acquire)) {
        finished.wait(done, std::memory_order_acquire);
      }
    }
    if (error) std::rethrow_exception(error);
  }

  std::vector<SnchQueryScratch> scratch;  // per thread
  std::vector<Task> tasks;
  std::vector<std::size_t> order;
  std::uint64_t revision = 0;
  double cutoff = 0.0;
  // The search being run (set before the helpers are woken).
  const CollisionWorld* world = nullptr;
  const arm::ArmData* fk = nullptr;
  bool coherent = false;
  std::atomic<std::size_t> next{0};
  std::atomic<std::uint64_t> generation{0};
  std::atomic<int> finished{0};
  std::atomic<bool> stop{false};
  std::mutex error_mutex;
  std::exception_ptr error;
  std::vector<std::thread> helpers;
};

SnchGlobalSearch::SnchGlobalSearch(const SnchSearchOptions& options) : options_(options) {
  if (options.threads < 1) {
    throw std::invalid_argument("SnchGlobalSearch: threads is " + std::to_string(options.threads) +
                                ", expected at least 1");
  }
  impl_ = std::make_unique<Impl>(options.threads);
}

SnchGlobalSearch::~SnchGlobalSearch() = default;

void SnchGlobalSearch::search(const CollisionWorld& world, const arm::ArmData& fk, double cutoff_m,
                              double prune_radius_m, std::vector<LocalMinimum>& out) {
  impl_->prepare(world, cutoff_m);
  impl_->runAll(world, fk, options_.coherent);
  out.clear();
  stats_ = {};
  for (const Impl::Task& t : impl_->tasks) {
    out.insert(out.end(), t.out.begin(), t.out.end());
    stats_.node_pairs_visited += t.stats.node_pairs_visited;
    stats_.pruned_by_distance += t.stats.pruned_by_distance;
    stats_.pruned_by_cone += t.stats.pruned_by_cone;
    stats_.pruned_by_convex_bound += t.stats.pruned_by_convex_bound;
    stats_.convex_hull_tests += t.stats.convex_hull_tests;
    stats_.triangle_pairs_tested += t.stats.triangle_pairs_tested;
    stats_.coherence_kept += t.stats.coherence_kept;
    stats_.coherence_rebuilds += t.stats.coherence_rebuilds;
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
