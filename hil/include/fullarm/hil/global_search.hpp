#pragma once
/// @file
/// Beside the tick: the global search that hands it new minima sets, and the missed-contact
/// oracle of lockstep runs. Neither is real-time code (they allocate while their storage grows).

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/haptics/bullet_search.hpp"
#include "fullarm/haptics/collision_world.hpp"
#include "fullarm/haptics/contact_forces.hpp"

namespace fullarm::hil {

/// The SNCH global search at a configuration, cutoff L and pruning radius r of the haptics
/// parameters (DTS paper section 3.2.1), keeping the tick's capacity of closest minima.
class GlobalSearchRunner {
 public:
  /// `model` and `world` must outlive the runner.
  GlobalSearchRunner(const arm::ArmModel& model, const haptics::CollisionWorld& world,
                     const haptics::HapticsParams& params);
  /// Replaces `out` with the minima at configuration `q` [rad]: all of them, or the
  /// kMaxTrackedMinima closest, in the search's order. Returns the number found before the cap.
  int run(const Eigen::VectorXd& q, std::vector<haptics::LocalMinimum>& out);
  /// Wall time of the last run() [s].
  [[nodiscard]] double lastSeconds() const noexcept { return last_s_; }

 private:
  const arm::ArmModel& model_;
  const haptics::CollisionWorld& world_;
  haptics::HapticsParams params_;
  arm::ArmData fk_;
  haptics::SnchGlobalSearch search_;
  std::vector<haptics::LocalMinimum> found_;
  double last_s_ = 0.0;
};

/// One tick at which a link came within d_f of an object while no tracked minimum covered that
/// link-object pair (the paper's central hazard: a contact the tick cannot render).
struct MissedContact {
  std::uint64_t tick = 0;
  int link = -1;
  int object = -1;
  double distance_m = 0.0;
};

/// The missed-contact oracle: at each checked tick an exact fresh query (SNCH, which the haptics
/// tests check against brute force and FCL) of every link against every object within d_f,
/// compared with the link-object pairs of the tracked minima. It also keeps the exact smallest
/// distance of each link over the run and, where a link touches an object, its penetration
/// depth (GJK/EPA).
class MissedContactOracle {
 public:
  MissedContactOracle(const arm::ArmModel& model, const haptics::CollisionWorld& world, double force_threshold_m);
  ~MissedContactOracle();
  /// Checks one tick at configuration `q`; returns the number of uncovered pairs within d_f.
  int check(std::uint64_t tick, const Eigen::VectorXd& q, std::span<const haptics::LocalMinimum> tracked);

  [[nodiscard]] std::uint64_t checkedTicks() const noexcept { return checked_; }
  /// Ticks with at least one uncovered pair.
  [[nodiscard]] std::uint64_t missedTicks() const noexcept { return missed_ticks_; }
  /// The first uncovered pairs found (at most 1000).
  [[nodiscard]] const std::vector<MissedContact>& missed() const noexcept { return missed_; }
  /// Per link: the smallest exact distance to any object over the checked ticks [m] (d_f when
  /// never closer).
  [[nodiscard]] const std::vector<double>& minDistance() const noexcept { return min_distance_m_; }
  /// Per link: the largest penetration depth into any object [m] and the time it spent
  /// touching or penetrating [ticks].
  [[nodiscard]] const std::vector<double>& maxPenetration() const noexcept { return max_penetration_m_; }
  [[nodiscard]] const std::vector<std::uint64_t>& penetrationTicks() const noexcept { return penetration_ticks_; }

 private:
  const arm::ArmModel& model_;
  const haptics::CollisionWorld& world_;
  double force_threshold_m_;
  arm::ArmData fk_;
  haptics::SnchGlobalSearch search_;
  std::unique_ptr<haptics::BulletGlobalSearch> penetration_;
  std::vector<haptics::LocalMinimum> found_;
  std::uint64_t checked_ = 0;
  std::uint64_t missed_ticks_ = 0;
  std::vector<MissedContact> missed_;
  std::vector<double> min_distance_m_;
  std::vector<double> max_penetration_m_;
  std::vector<std::uint64_t> penetration_ticks_;
};

}  // namespace fullarm::hil
