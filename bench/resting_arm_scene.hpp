#pragma once
// The scene of the local-tick benchmarks (bench/haptics_local_bench.cpp and
// bench/hil_tick_bench.cpp measure on the same one): the default DTS arm at its default posture
// resting 6 mm above rough ledges under and beside the upper arm, forearm and hand; 64 tracked
// minima found at q0 (cutoff 6 cm, pruning radius 2 mm), updated at q1 = q0 + delta on every
// joint (the benchmark's Arg: delta in millidegrees; 57 = one 1 ms tick at 1 rad/s).

#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/local_descent.hpp"
#include "fullarm/haptics/primitives.hpp"

namespace fullarm::bench {

inline constexpr std::size_t kMinima = 64;
inline constexpr double kPruneRadius_m = 0.002;

/// q1 = q0 + (state.range(0) millidegrees) on every joint: one tick of motion.
inline Eigen::VectorXd motion(const Eigen::VectorXd& q0, const benchmark::State& state) {
  Eigen::VectorXd q1 = q0;
  q1.array() += static_cast<double>(state.range(0)) * 1e-3 * 3.14159265358979 / 180.0;
  return q1;
}

/// A box whose top face (1 cm triangles) carries +-1.5 mm of seeded random relief: every bump
/// under a link is a separate local minimum in general position (a flat parallel face would be
/// the degenerate case where all minima slide together).
inline haptics::TriMesh roughBox(const Eigen::Vector3d& size_m, std::mt19937& rng) {
  const haptics::TriMesh box = haptics::makeBox(size_m, 0.01);
  std::vector<Eigen::Vector3d> v;
  std::vector<Eigen::Vector3i> t;
  std::uniform_real_distribution<double> bump(-0.0015, 0.0015);
  for (int i = 0; i < box.numVertices(); ++i) {
    Eigen::Vector3d p = box.vertex(i);
    const bool interior_top =
        p.z() > 0.0 && std::abs(p.x()) < 0.5 * size_m.x() - 1e-9 && std::abs(p.y()) < 0.5 * size_m.y() - 1e-9;
    if (interior_top) p.z() += bump(rng);
    v.push_back(p);
  }
  for (int i = 0; i < box.numTriangles(); ++i) t.push_back(box.triangle(i));
  return haptics::TriMesh::build("rough ledge", std::move(v), std::move(t));
}

/// Adds the ledges to every world of `worlds` (the same meshes and poses): for the upper arm,
/// the forearm and the hand, one dense box whose top face runs parallel to the link capsule 6 mm
/// below it (a resting contact) and one beside it (normals perpendicular to the link).
inline void addLedges(const arm::ArmModel& model, const arm::ArmData& fk,
                      std::initializer_list<haptics::CollisionWorld*> worlds) {
  std::mt19937 rng(42);
  for (const int l : {2, 4, 6}) {
    const arm::LinkGeometry& g = model.joints[static_cast<std::size_t>(l)].geometry;
    const Eigen::Isometry3d& X = fk.X_WL[static_cast<std::size_t>(l)];
    const Eigen::Vector3d a = X * g.from_m;
    const Eigen::Vector3d b = X * g.to_m;
    const Eigen::Vector3d axis = (b - a).normalized();
    Eigen::Vector3d up = Eigen::Vector3d::UnitZ() - Eigen::Vector3d::UnitZ().dot(axis) * axis;
    up.normalize();
    for (const Eigen::Vector3d& n : {up, Eigen::Vector3d(up.cross(axis))}) {
      Eigen::Isometry3d X_WO = Eigen::Isometry3d::Identity();
      X_WO.linear().col(0) = axis;
      X_WO.linear().col(1) = n.cross(axis);
      X_WO.linear().col(2) = n;
      X_WO.translation() = 0.5 * (a + b) - (g.radius_m + 0.006 + 0.01) * n;
      const haptics::TriMesh ledge = roughBox({std::max(0.06, (b - a).norm() - 0.06), 0.08, 0.02}, rng);
      for (haptics::CollisionWorld* world : worlds) world->addObject("ledge_" + std::to_string(l), ledge, X_WO);
    }
  }
}

/// The 64 minima spread over the fresh search's set of `world` at fk (none touching).
inline std::vector<haptics::LocalMinimum> baselineMinima(const haptics::CollisionWorld& world, const arm::ArmData& fk) {
  std::vector<haptics::LocalMinimum> all;
  haptics::globalSearch(world, fk, 0.06, kPruneRadius_m, all);
  if (all.size() < kMinima) throw std::runtime_error("bench scene has too few minima: " + std::to_string(all.size()));
  for (const auto& m : all) {
    if (m.distance_m <= 0.0) {
      throw std::runtime_error("bench scene: link " + std::to_string(m.link) + " touches object " +
                               std::to_string(m.object));
    }
  }
  std::vector<haptics::LocalMinimum> baseline;
  for (std::size_t i = 0; i < kMinima; ++i) baseline.push_back(all[i * all.size() / kMinima]);
  return baseline;
}

/// The median and p99 of per-iteration times as the benchmark's counters (median_us, p99_us).
inline void reportPercentiles(benchmark::State& state, std::vector<double>& us) {
  if (us.empty()) return;
  std::sort(us.begin(), us.end());
  state.counters["median_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
}

}  // namespace fullarm::bench
