// The motion benchmark of the global search: the recorded 10 s approach of the DTS arm through
// the wall opening of scenes/valve_wall.yaml to the wheel valve and back
// (scenes/valve_wall_approach.csv, 1,001 postures at 100 Hz, written by
// bench/valve_approach_motion.cpp), replayed as one global search per posture, on the valve scene
// (16,611 triangles) and on the same scene with every object midpoint-subdivided three times
// (1,063,104 triangles). The arm enters and leaves contacts with the opening's frame, the truss
// and the wheel; the queries are timed one by one (steady_clock around GlobalSearch::search, the
// forward kinematics outside), and per replay the median, p99 and max of the warm queries are
// reported apart from the cold one (the first query of a fresh search object: nothing cached,
// memory cold). Each variant runs --reps replays; the table gives the median over replays of each
// figure, and [min, max] of the p99.
//
// Variants (--variants, comma-separated): the SNCH search fresh and sequential (`snch`), with
// the coherence of successive queries (`snch-coherent`), on two threads (`snch-2t`), both
// (`snch-coherent-2t`); the peers `bullet` (BulletGlobalSearch: Bullet's BVH and the same exact
// tests) and `fcl` (FCL 0.7's capsule-mesh distance, OBBRSS BVH, one global minimum per link x
// object pair, for every pair of the query). Before timing, every SNCH variant and the Bullet
// peer are checked to return exactly the minima of `snch` on every posture of the motion.
// --every N replays every Nth posture only (for slow peers on the large scene; the cold query is
// still the first).
//
// The tick under load (--tick): the 1 kHz haptic tick (forward kinematics, local descent of the
// tracked minima, springs, Eq. (1)-(2) torques, gravity) replays the motion interpolated to
// 1 kHz on one core while a global search thread replays it at 100 Hz (each search starting
// at the tick's latest posture, its minima adopted by the tick) on the other; the tick's median,
// p99 and max are reported with the search idle, sequential and on two threads.
//
// Built against another tree with -DFULLARM_MOTION_BENCH_BASELINE, only `snch` and `bullet` are
// available (the comparison with an earlier version of the search, run alternately).
//
// build/release/bench/haptics_motion_bench --scene valve --reps 5
// build/release/bench/haptics_motion_bench --scene 1m --reps 3
// build/release/bench/haptics_motion_bench --scene valve --tick
#include <fcl/narrowphase/distance.h>
#include <pthread.h>
#include <sched.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "fcl_mesh.hpp"  // tests/haptics: the FCL peer's mesh and capsule
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/bullet_search.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/local_descent.hpp"
#include "fullarm/haptics/mesh_subdivision.hpp"
#include "fullarm/haptics/scene.hpp"

namespace {

using namespace fullarm;
using Clock = std::chrono::steady_clock;

constexpr double kCutoff_m = 0.03;       // config/haptics.yaml
constexpr double kPruneRadius_m = 0.02;  // config/haptics.yaml

std::filesystem::path sourceFile(const char* relative) {
  return std::filesystem::path(FULLARM_SOURCE_DIR) / relative;
}

// The recorded motion: joint angles of the arm's first joints per sample (the others keep the
// model's default posture).
std::vector<Eigen::VectorXd> loadMotion(const std::filesystem::path& file, const arm::ArmModel& model) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open");
  std::vector<Eigen::VectorXd> motion;
  std::string line;
  bool header = true;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (header) {
      header = false;
      continue;
    }
    std::istringstream row(line);
    std::string cell;
    std::getline(row, cell, ',');  // t_s
    Eigen::VectorXd q = model.defaultPosture();
    for (int j = 0; std::getline(row, cell, ','); ++j) q[j] = std::stod(cell);
    motion.push_back(q);
  }
  if (motion.empty()) throw std::runtime_error(file.string() + ": no sample");
  return motion;
}

// The scene with every object midpoint-subdivided `levels` times.
haptics::Scene subdivided(haptics::Scene scene, int levels) {
  for (haptics::SceneObject& o : scene.objects) o.mesh = haptics::subdivideMidpoint(o.mesh, levels);
  return scene;
}

struct Setup {
  arm::ArmModel model = arm::loadArmModel(sourceFile("config/dts_master.yaml"));
  haptics::Scene scene;
  std::unique_ptr<haptics::CollisionWorld> world;
  std::vector<Eigen::VectorXd> motion = loadMotion(sourceFile("scenes/valve_wall_approach.csv"), model);
  std::vector<arm::ArmData> fk;  // per sample
  double build_s = 0.0;          // time to build the collision world (hierarchies, cones)

  Setup(const std::string& which) {
    const haptics::Scene valve = haptics::loadScene(sourceFile("scenes/valve_wall.yaml"));
    scene = which == "1m" ? subdivided(valve, 3) : valve;
    const auto t0 = Clock::now();
    world = std::make_unique<haptics::CollisionWorld>(haptics::makeCollisionWorld(scene, model));
    build_s = std::chrono::duration<double>(Clock::now() - t0).count();
    for (const Eigen::VectorXd& q : motion) {
      fk.emplace_back(model);
      arm::computeForwardKinematics(model, fk.back(), q);
    }
  }
};

// Per-query times of one replay [ms]: wall clock, and the CPU time of the calling thread
// (CLOCK_THREAD_CPUTIME_ID: what the query cost that thread, without the time other processes
// held the core; on two threads the helper's share is not in it).
struct Replay {
  double cold_ms = 0.0;
  std::vector<double> warm_ms;
  std::vector<double> warm_cpu_ms;
};

struct Summary {
  double cold = 0.0;
  double median = 0.0;
  double p99 = 0.0;
  double max = 0.0;
  double cpu_median = 0.0;
  double cpu_p99 = 0.0;
};

double threadCpuMs() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return 1e3 * static_cast<double>(t.tv_sec) + 1e-6 * static_cast<double>(t.tv_nsec);
}

double percentile(std::vector<double> v, double p) {
  std::sort(v.begin(), v.end());
  const auto k =
      static_cast<std::size_t>(std::min<double>(static_cast<double>(v.size() - 1), p * static_cast<double>(v.size())));
  return v[k];
}

Summary summarise(const Replay& r) {
  return {r.cold_ms,
          percentile(r.warm_ms, 0.5),
          percentile(r.warm_ms, 0.99),
          *std::max_element(r.warm_ms.begin(), r.warm_ms.end()),
          percentile(r.warm_cpu_ms, 0.5),
          percentile(r.warm_cpu_ms, 0.99)};
}

// A search to replay: a fresh object per replay (the cold query is its first).
using SearchFactory = std::function<std::unique_ptr<haptics::GlobalSearch>()>;

std::vector<std::size_t> postures(const Setup& s, int every) {
  std::vector<std::size_t> k;
  for (std::size_t i = 0; i < s.motion.size(); i += static_cast<std::size_t>(every)) k.push_back(i);
  return k;
}

Replay replay(const Setup& s, haptics::GlobalSearch& search, const std::vector<std::size_t>& which) {
  Replay r;
  std::vector<haptics::LocalMinimum> out;
  for (std::size_t i = 0; i < which.size(); ++i) {
    const double cpu0 = threadCpuMs();
    const auto t0 = Clock::now();
    search.search(*s.world, s.fk[which[i]], kCutoff_m, kPruneRadius_m, out);
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
    const double cpu = threadCpuMs() - cpu0;
    if (i == 0) {
      r.cold_ms = ms;
    } else {
      r.warm_ms.push_back(ms);
      r.warm_cpu_ms.push_back(cpu);
    }
  }
  return r;
}

// FCL peer: capsule (or faceted mesh) of every link with geometry against every object, one
// fcl::distance per pair and query (global minimum only).
class FclPeer final : public haptics::GlobalSearch {
 public:
  explicit FclPeer(const haptics::CollisionWorld& world) {
    for (int o = 0; o < world.numObjects(); ++o) objects_.push_back(haptics::test::fclModel(world.object(o).mesh));
    links_.resize(static_cast<std::size_t>(world.numLinks()));
    for (int l = 0; l < world.numLinks(); ++l) {
      Shape& link = links_[static_cast<std::size_t>(l)];
#ifndef FULLARM_MOTION_BENCH_BASELINE
      if (world.linkShape(l) == haptics::LinkShape::kCapsule) {
        const haptics::test::FclCapsule c = haptics::test::fclCapsule(world.linkCapsule(l));
        link = {c.shape, c.X_LC};
        continue;
      }
#endif
      if (world.hasLinkMesh(l)) link.shape = haptics::test::fclModel(world.linkMesh(l));
    }
  }
  void search(const haptics::CollisionWorld& world, const arm::ArmData& fk, double /*cutoff_m*/, double /*r*/,
              std::vector<haptics::LocalMinimum>& out) override {
    out.clear();
    for (std::size_t l = 0; l < links_.size(); ++l) {
      if (!links_[l].shape) continue;
      for (int o = 0; o < world.numObjects(); ++o) {
        fcl::CollisionObjectd a(links_[l].shape, fk.X_WL[l] * links_[l].X_LC);
        fcl::CollisionObjectd b(objects_[static_cast<std::size_t>(o)], world.object(o).X_WO);
        fcl::DistanceRequestd req;
        fcl::DistanceResultd res;
        fcl::distance(&a, &b, req, res);
        sum_ += res.min_distance;
      }
    }
  }
  [[nodiscard]] std::string_view name() const noexcept override {
    return "fcl";
  }
  double sum_ = 0.0;

 private:
  struct Shape {
    std::shared_ptr<fcl::CollisionGeometryd> shape;
    Eigen::Isometry3d X_LC = Eigen::Isometry3d::Identity();
  };
  std::vector<std::shared_ptr<fcl::BVHModel<fcl::OBBRSSd>>> objects_;
  std::vector<Shape> links_;
};

std::map<std::string, SearchFactory> variants(const Setup& s) {
  std::map<std::string, SearchFactory> v;
#ifdef FULLARM_MOTION_BENCH_BASELINE
  v["snch"] = [] { return std::make_unique<haptics::SnchGlobalSearch>(); };
#else
  auto snch = [](int threads, bool coherent) -> SearchFactory {
    return [threads, coherent] {
      return std::make_unique<haptics::SnchGlobalSearch>(haptics::SnchSearchOptions{threads, coherent});
    };
  };
  v["snch"] = snch(1, false);
  v["snch-coherent"] = snch(1, true);
  v["snch-2t"] = snch(2, false);
  v["snch-coherent-2t"] = snch(2, true);
#endif
  v["bullet"] = [&s] { return std::make_unique<haptics::BulletGlobalSearch>(*s.world); };
  v["fcl"] = [&s] { return std::make_unique<FclPeer>(*s.world); };
  return v;
}

bool sameMinima(const std::vector<haptics::LocalMinimum>& a, const std::vector<haptics::LocalMinimum>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (!haptics::sameFeaturePair(a[i], b[i]) || a[i].distance_m != b[i].distance_m || a[i].p_L != b[i].p_L ||
        a[i].p_O != b[i].p_O) {
      return false;
    }
  }
  return true;
}

// Every SNCH variant and Bullet return the minima of the fresh sequential search on every posture.
void checkSameMinima(const Setup& s, const std::string& name, const SearchFactory& make,
                     const std::vector<std::size_t>& which) {
  if (name == "fcl") return;
  const auto reference = variants(s).at("snch")();
  const auto search = make();
  std::vector<haptics::LocalMinimum> a;
  std::vector<haptics::LocalMinimum> b;
  for (const std::size_t k : which) {
    reference->search(*s.world, s.fk[k], kCutoff_m, kPruneRadius_m, a);
    search->search(*s.world, s.fk[k], kCutoff_m, kPruneRadius_m, b);
    const bool same = name == "bullet" ? a.size() == b.size() : sameMinima(a, b);
    if (!same) {
      throw std::runtime_error(name + " returned other minima than the fresh sequential search at posture " +
                               std::to_string(k) + ": the comparison is void");
    }
  }
}

void runQueries(const Setup& s, const std::vector<std::string>& names, int reps, int every) {
  const auto all = variants(s);
  const std::vector<std::size_t> which = postures(s, every);
  std::printf("%-18s %8s %8s %8s %8s %8s %8s %8s %8s  (ms; %zu queries per replay, %d replays)\n", "variant", "cold",
              "median", "p99", "p99 min", "p99 max", "max", "cpu med", "cpu p99", which.size(), reps);
  for (const std::string& name : names) {
    const auto it = all.find(name);
    if (it == all.end()) throw std::runtime_error("unknown variant " + name);
    checkSameMinima(s, name, it->second, which);
    std::vector<Summary> runs;
    for (int r = 0; r < reps; ++r) {
      const auto search = it->second();
      runs.push_back(summarise(replay(s, *search, which)));
    }
    auto med = [&](double Summary::*f) {
      std::vector<double> v;
      for (const Summary& x : runs) v.push_back(x.*f);
      return percentile(v, 0.5);
    };
    std::vector<double> p99;
    for (const Summary& x : runs) p99.push_back(x.p99);
    std::printf("%-18s %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f %8.3f\n", name.c_str(), med(&Summary::cold),
                med(&Summary::median), med(&Summary::p99), *std::min_element(p99.begin(), p99.end()),
                *std::max_element(p99.begin(), p99.end()), med(&Summary::max), med(&Summary::cpu_median),
                med(&Summary::cpu_p99));
    std::fflush(stdout);
  }
}

// ---------------------------------------------------------------------------------------------
// The tick under load.

void pinTo(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  pthread_setaffinity_np(pthread_self(), sizeof(set), &set);
}

// The motion's posture at time t [s], linear between the 100 Hz samples.
Eigen::VectorXd postureAt(const std::vector<Eigen::VectorXd>& motion, double t) {
  const double x = std::clamp(t * 100.0, 0.0, static_cast<double>(motion.size() - 1));
  const auto k = static_cast<std::size_t>(x);
  if (k + 1 >= motion.size()) return motion.back();
  return motion[k] + (x - static_cast<double>(k)) * (motion[k + 1] - motion[k]);
}

struct TickRun {
  std::vector<double> tick_us;    // per tick: kinematics, adoption, descent, springs, torques, gravity
  std::vector<double> search_ms;  // per global search (wall)
  int adopted = 0;
};

// The 1 kHz tick over the motion on CPU 0 and, when `search` is set, a global search thread on
// CPU 1 starting a search every `period_ms` (0: back to back) at the tick's latest posture.
// Without a search the tick adopts, every 10 ms, the minima a search computed beforehand at the
// posture of that moment (the same work on the tick's side, nothing running beside it).
TickRun runTick(const Setup& s, haptics::GlobalSearch* search, double period_ms) {
  const arm::ArmModel& model = s.model;
  const haptics::HapticsParams params = haptics::loadHapticsParams(sourceFile("config/haptics.yaml"));
  const double duration_s = static_cast<double>(s.motion.size() - 1) / 100.0;
  const int ticks = static_cast<int>(duration_s * 1000.0);
  TickRun run;
  run.tick_us.reserve(static_cast<std::size_t>(ticks));
  std::mutex mutex;  // guards latest_q and fresh
  Eigen::VectorXd latest_q = s.motion.front();
  std::vector<haptics::LocalMinimum> fresh;
  bool fresh_ready = false;
  std::atomic<bool> done{false};
  std::thread searcher;
  if (search != nullptr) {
    searcher = std::thread([&] {
      pinTo(1);
      arm::ArmData fk(model);
      std::vector<haptics::LocalMinimum> out;
      auto next = Clock::now();
      while (!done.load()) {
        Eigen::VectorXd q;
        {
          const std::lock_guard<std::mutex> lock(mutex);
          q = latest_q;
        }
        arm::computeForwardKinematics(model, fk, q);
        const auto t0 = Clock::now();
        search->search(*s.world, fk, params.cutoff_m, params.prune_radius_m, out);
        run.search_ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
        {
          const std::lock_guard<std::mutex> lock(mutex);
          fresh = out;
          fresh_ready = true;
        }
        if (period_ms > 0.0) {
          next += std::chrono::microseconds(static_cast<long>(1e3 * period_ms));
          std::this_thread::sleep_until(next);
        }
      }
    });
  }
  pinTo(0);
  arm::ArmData fk(model);
  haptics::ContactData contact(model, 512);
  std::vector<haptics::LocalMinimum> tracked;
  tracked.reserve(512);
  std::vector<haptics::LocalMinimum> incoming;
  std::vector<std::vector<haptics::LocalMinimum>> precomputed;
  if (search == nullptr) {
    haptics::SnchGlobalSearch offline;
    for (std::size_t k = 0; k < s.motion.size(); ++k) {
      precomputed.emplace_back();
      offline.search(*s.world, s.fk[k], params.cutoff_m, params.prune_radius_m, precomputed.back());
    }
  }
  auto next = Clock::now();
  for (int k = 0; k < ticks; ++k) {
    const Eigen::VectorXd q = postureAt(s.motion, 1e-3 * k);
    const auto t0 = Clock::now();
    arm::computeForwardKinematics(model, fk, q);
    // The hand-off (try_lock: a tick never waits for the search).
    bool adopt = false;
    if (search == nullptr) {
      if (k % 10 == 1) {
        incoming = precomputed[static_cast<std::size_t>(k / 10)];
        adopt = true;
      }
    } else if (mutex.try_lock()) {
      latest_q = q;
      if (fresh_ready) {
        incoming.swap(fresh);
        fresh_ready = false;
        adopt = true;
      }
      mutex.unlock();
    }
    if (adopt) run.adopted += haptics::adoptGlobalMinima(tracked, incoming, params.prune_radius_m);
    const int kept = haptics::updateMinimaLocalDescent(*s.world, fk, tracked, params.descent);
    tracked.resize(static_cast<std::size_t>(std::min(kept, 512)));
    haptics::computeContactForces(params, model, fk, tracked, 1e-3, contact);
    haptics::computeContactTorques(model, fk, tracked, contact);
    arm::computeGravityTorquesAtKinematics(model, fk);
    run.tick_us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
  done.store(true);
  if (searcher.joinable()) searcher.join();
  return run;
}

void runTicks(const Setup& s) {
  struct Case {
    const char* name;
    int threads;  // 0: no search
    double period_ms;
  };
#ifdef FULLARM_MOTION_BENCH_BASELINE
  const std::vector<Case> cases = {
      {"no search beside", 0, 0.0}, {"search 100 Hz", 1, 10.0}, {"search back to back", 1, 0.0}};
#else
  const std::vector<Case> cases = {{"no search beside", 0, 0.0},
                                   {"search 100 Hz", 1, 10.0},
                                   {"search back to back", 1, 0.0},
                                   {"search 100 Hz, 2 threads", 2, 10.0},
                                   {"search back to back, 2 threads", 2, 0.0}};
#endif
  std::printf("%-32s %9s %9s %9s %9s %9s %9s  (tick us on CPU 0; search ms on CPU 1)\n", "case", "tick med", "tick p99",
              "tick max", "searches", "srch med", "srch p99");
  for (const Case& c : cases) {
    std::unique_ptr<haptics::GlobalSearch> search;
    if (c.threads > 0) {
#ifdef FULLARM_MOTION_BENCH_BASELINE
      search = std::make_unique<haptics::SnchGlobalSearch>();
#else
      // Constructed here (no affinity): a helper thread may run on either core.
      search = std::make_unique<haptics::SnchGlobalSearch>(haptics::SnchSearchOptions{c.threads, true});
#endif
    }
    const TickRun r = runTick(s, search.get(), c.period_ms);
    const bool any = !r.search_ms.empty();
    std::printf("%-32s %9.2f %9.2f %9.2f %9zu %9.3f %9.3f\n", c.name, percentile(r.tick_us, 0.5),
                percentile(r.tick_us, 0.99), *std::max_element(r.tick_us.begin(), r.tick_us.end()), r.search_ms.size(),
                any ? percentile(r.search_ms, 0.5) : 0.0, any ? percentile(r.search_ms, 0.99) : 0.0);
    std::fflush(stdout);
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::string scene = "valve";
  std::string names = "snch,bullet,fcl";
  int reps = 5;
  int every = 1;
  bool tick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) throw std::runtime_error(a + " needs a value");
      return argv[++i];
    };
    if (a == "--scene") {
      scene = value();
    } else if (a == "--variants") {
      names = value();
    } else if (a == "--reps") {
      reps = std::stoi(value());
    } else if (a == "--every") {
      every = std::stoi(value());
    } else if (a == "--tick") {
      tick = true;
    } else {
      std::cerr << "usage: haptics_motion_bench [--scene valve|1m] [--variants a,b,...] [--reps N] [--every N] "
                   "[--tick]\n";
      return 2;
    }
  }
  const Setup s(scene);
  std::printf("scene %s: %ld triangles, %zu postures; collision world built in %.2f s\n", scene.c_str(),
              s.scene.numTriangles(), s.motion.size(), s.build_s);
  if (tick) {
    runTicks(s);
    return 0;
  }
  std::vector<std::string> list;
  std::istringstream in(names);
  for (std::string n; std::getline(in, n, ',');) list.push_back(n);
  runQueries(s, list, reps, every);
  return 0;
}
