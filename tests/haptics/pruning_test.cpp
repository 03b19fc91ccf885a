// Endpoint-radius pruning on a flat, densely triangulated wall (DTS paper section 3.2.1):
// - a capsule link lying parallel to the wall floods the search with face-face minima; after
//   pruning the count is bounded by the contact patch area over pi r^2 (patch: the wall region
//   within the cutoff of the ideal capsule, which contains the faceted one);
// - a link sliding across triangle boundaries under local descent, with global refreshes
//   merged through adoptGlobalMinima, feels a continuous force (step-to-step jump < 1%).
#include <gtest/gtest.h>

#include <numbers>

#include "arm_test_util.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"
#include "fullarm/haptics/local_descent.hpp"
#include "fullarm/haptics/primitives.hpp"

namespace fullarm::haptics {
namespace {

using Eigen::Isometry3d;
using Eigen::Vector3d;

constexpr int kLink = 4;  // forearm: the test attaches its own capsule
constexpr double kRadius_m = 0.04;
constexpr double kLength_m = 0.28;

struct Wall {
  CollisionWorld world;
  arm::ArmData fk;
  explicit Wall(const arm::ArmModel& model) : world(model), fk(model) {
    for (std::size_t i = 0; i < fk.X_WL.size(); ++i) {
      fk.X_WL[i] = Eigen::Translation3d(100.0 * static_cast<double>(i + 1), 50.0, 0.0) * Isometry3d::Identity();
    }
    world.setLinkMesh(kLink, makeCapsule({0, 0, 0}, {0, 0, kLength_m}, kRadius_m, 16, 4));
    // Wall top face at z = 0, 1.25 cm triangles: 12 800 on the face, about 26 000 in all.
    world.addObject("wall", makeBox({1.0, 1.0, 0.02}, 0.0125),
                    Eigen::Translation3d(0, 0, -0.01) * Isometry3d::Identity());
  }
};

// Capsule axis along world x, lowest point `gap_m` above the wall, rolled by `roll_rad`.
Isometry3d lyingPose(double gap_m, double roll_rad, double x0_m) {
  Isometry3d X = Isometry3d::Identity();
  X.linear() =
      (Eigen::AngleAxisd(std::numbers::pi / 2, Vector3d::UnitY()) * Eigen::AngleAxisd(roll_rad, Vector3d::UnitZ()))
          .toRotationMatrix();
  X.translation() = Vector3d(x0_m - 0.5 * kLength_m, 0.0013, kRadius_m + gap_m);
  return X;
}

TEST(PruningTest, AcceptedMinimaBoundedByPatchAreaOverPiRSquared) {
  const arm::ArmModel& model = arm::test::defaultModel();
  Wall w(model);
  constexpr double kCutoff_m = 0.03;
  constexpr double kGap_m = 0.005;
  // Ideal capsule: wall points within R + L of the axis, axis at height R + gap.
  const double half_width = std::sqrt(std::pow(kRadius_m + kCutoff_m, 2) - std::pow(kRadius_m + kGap_m, 2));
  const double patch_area = kLength_m * 2.0 * half_width + std::numbers::pi * half_width * half_width;
  std::size_t max_unpruned = 0;
  for (const double roll : {std::numbers::pi / 16, 0.37}) {
    w.fk.X_WL[kLink] = lyingPose(kGap_m, roll, 0.0);
    std::vector<LocalMinimum> unpruned;
    globalSearch(w.world, w.fk, kCutoff_m, 0.0, unpruned);
    for (const double r : {0.01, 0.03}) {
      std::vector<LocalMinimum> pruned;
      globalSearch(w.world, w.fk, kCutoff_m, r, pruned);
      const double bound = patch_area / (std::numbers::pi * r * r);
      EXPECT_LE(static_cast<double>(pruned.size()), bound) << "roll " << roll << " r " << r;
      EXPECT_GE(pruned.size(), 1u);
      // Accepted minima are pairwise separated on at least one side by more than r.
      for (std::size_t i = 0; i < pruned.size(); ++i) {
        for (std::size_t j = 0; j < i; ++j) {
          const bool near = (pruned[i].p_L - pruned[j].p_L).norm() <= r && (pruned[i].p_O - pruned[j].p_O).norm() <= r;
          EXPECT_FALSE(near);
        }
      }
      RecordProperty("unpruned_roll_" + std::to_string(roll), static_cast<int>(unpruned.size()));
    }
    max_unpruned = std::max(max_unpruned, unpruned.size());
  }
  // A facet lying parallel to the wall floods the unpruned search (what pruning is for).
  EXPECT_GT(static_cast<double>(max_unpruned), patch_area / (std::numbers::pi * 0.02 * 0.02));
}

// Slides the link 5 cm along x in 0.5 mm steps (1 kHz ticks), global refresh every 10 ticks.
// Returns the largest step-to-step change of the total contact force relative to its size.
double slideAndMeasureJump(Wall& w, const Isometry3d& X0, const HapticsParams& params, int* min_springs) {
  const arm::ArmModel& model = w.world.model();
  ContactData data(model, 256);
  std::vector<LocalMinimum> tracked;
  Isometry3d X = X0;
  Vector3d previous = Vector3d::Zero();
  double worst = 0.0;
  *min_springs = 1 << 20;
  for (int tick = 0; tick < 100; ++tick) {
    w.fk.X_WL[kLink] = X;
    if (tick % 10 == 0) {
      std::vector<LocalMinimum> fresh;
      globalSearch(w.world, w.fk, params.cutoff_m, params.prune_radius_m, fresh);
      adoptGlobalMinima(tracked, std::move(fresh), params.prune_radius_m);
    }
    const int kept = updateMinimaLocalDescent(w.world, w.fk, tracked, params.descent);
    tracked.resize(static_cast<std::size_t>(kept));
    computeContactForces(params, model, w.fk, tracked, 1e-3, data);
    EXPECT_TRUE(data.status.ok());
    Vector3d total = Vector3d::Zero();
    for (std::size_t i = 0; i < tracked.size(); ++i) total += data.f_W[i];
    *min_springs = std::min(*min_springs, data.active_springs);
    if (tick > 0) worst = std::max(worst, (total - previous).norm() / total.norm());
    previous = total;
    X.translation().x() += 0.0005;
  }
  return worst;
}

TEST(PruningTest, ForceIsContinuousWhileSlidingAcrossTriangles) {
  const arm::ArmModel& model = arm::test::defaultModel();
  HapticsParams params;  // k = 2000 N/m, d_f = 10 mm, L = 30 mm, r = 20 mm
  // Tilted link: the end cap touches (general position).
  {
    Wall w(model);
    Isometry3d X0 = lyingPose(0.004, 0.2, 0.0);
    X0.linear() = Eigen::AngleAxisd(0.3, Vector3d::UnitY()).toRotationMatrix() * X0.linear();
    X0.translation().z() = 0.0;
    // Lift it so its lowest vertex is 4 mm above the wall.
    double lowest = std::numeric_limits<double>::infinity();
    for (int v = 0; v < w.world.linkMesh(kLink).numVertices(); ++v) {
      lowest = std::min(lowest, (X0 * w.world.linkMesh(kLink).vertex(v)).z());
    }
    X0.translation().z() = 0.004 - lowest;
    int springs = 0;
    const double jump = slideAndMeasureJump(w, X0, params, &springs);
    EXPECT_LT(jump, 0.01);
    EXPECT_GE(springs, 1);
    RecordProperty("tilted_jump", std::to_string(jump));
  }
  // Lying flat with per-patch stiffness normalisation.
  {
    Wall w(model);
    params.normalise_per_patch = true;
    params.patch_radius_m = 0.05;  // > r + triangle size: the line contact stays one patch
    int springs = 0;
    const double jump = slideAndMeasureJump(w, lyingPose(0.004, 0.0, 0.0), params, &springs);
    EXPECT_GE(springs, 1);
    RecordProperty("flat_normalised_jump", std::to_string(jump));
    EXPECT_LT(jump, 0.01);
  }
  // For the record: the same flat slide without normalisation (each minimum a full spring).
  {
    Wall w(model);
    params.normalise_per_patch = false;
    int springs = 0;
    const double jump = slideAndMeasureJump(w, lyingPose(0.004, 0.0, 0.0), params, &springs);
    RecordProperty("flat_unnormalised_jump", std::to_string(jump));
  }
}

}  // namespace
}  // namespace fullarm::haptics
