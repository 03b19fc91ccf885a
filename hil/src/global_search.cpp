#include "fullarm/hil/global_search.hpp"

#include <algorithm>
#include <chrono>

#include "fullarm/arm/kinematics.hpp"
#include "fullarm/hil/tick.hpp"

namespace fullarm::hil {

GlobalSearchRunner::GlobalSearchRunner(const arm::ArmModel& model, const haptics::CollisionWorld& world,
                                       const haptics::HapticsParams& params)
    : model_(model), world_(world), params_(params), fk_(model) {}

int GlobalSearchRunner::run(const Eigen::VectorXd& q, std::vector<haptics::LocalMinimum>& out) {
  const auto start = std::chrono::steady_clock::now();
  arm::computeForwardKinematics(model_, fk_, q);
  search_.search(world_, fk_, params_.cutoff_m, params_.prune_radius_m, found_);
  const int found = static_cast<int>(found_.size());
  out.clear();
  if (found <= kMaxTrackedMinima) {
    out.assign(found_.begin(), found_.end());
  } else {
    // Keep the closest, in the search's order.
    std::vector<double> d;
    d.reserve(found_.size());
    for (const haptics::LocalMinimum& m : found_) d.push_back(m.distance_m);
    std::nth_element(d.begin(), d.begin() + (kMaxTrackedMinima - 1), d.end());
    const double cut = d[kMaxTrackedMinima - 1];
    for (const haptics::LocalMinimum& m : found_) {
      if (m.distance_m < cut && static_cast<int>(out.size()) < kMaxTrackedMinima) out.push_back(m);
    }
    for (const haptics::LocalMinimum& m : found_) {
      if (m.distance_m == cut && static_cast<int>(out.size()) < kMaxTrackedMinima) out.push_back(m);
    }
  }
  last_s_ = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return found;
}

MissedContactOracle::MissedContactOracle(const arm::ArmModel& model, const haptics::CollisionWorld& world,
                                         double force_threshold_m)
    : model_(model),
      world_(world),
      force_threshold_m_(force_threshold_m),
      fk_(model),
      penetration_(std::make_unique<haptics::BulletGlobalSearch>(world)),
      min_distance_m_(static_cast<std::size_t>(model.numJoints()), force_threshold_m),
      max_penetration_m_(static_cast<std::size_t>(model.numJoints()), 0.0),
      penetration_ticks_(static_cast<std::size_t>(model.numJoints()), 0) {}

MissedContactOracle::~MissedContactOracle() = default;

int MissedContactOracle::check(std::uint64_t tick, const Eigen::VectorXd& q,
                               std::span<const haptics::LocalMinimum> tracked) {
  arm::computeForwardKinematics(model_, fk_, q);
  // Every minimum within d_f, unpruned: the exact set of close link-object pairs.
  search_.search(world_, fk_, force_threshold_m_, 0.0, found_);
  ++checked_;
  int uncovered = 0;
  std::vector<std::pair<int, int>> touching;
  for (const haptics::LocalMinimum& m : found_) {
    const std::size_t l = static_cast<std::size_t>(m.link);
    min_distance_m_[l] = std::min(min_distance_m_[l], m.distance_m);
    if (m.distance_m <= 0.0) touching.emplace_back(m.link, m.object);
    const bool covered = std::any_of(tracked.begin(), tracked.end(), [&](const haptics::LocalMinimum& t) {
      return t.link == m.link && t.object == m.object;
    });
    if (!covered && m.distance_m < force_threshold_m_) {
      ++uncovered;
      if (missed_.size() < 1000) missed_.push_back({tick, m.link, m.object, m.distance_m});
    }
  }
  std::sort(touching.begin(), touching.end());
  touching.erase(std::unique(touching.begin(), touching.end()), touching.end());
  std::vector<bool> link_touching(static_cast<std::size_t>(model_.numJoints()), false);
  for (const auto& [link, object] : touching) {
    const haptics::LinkPenetration p = penetration_->penetration(link, fk_.X_WL[static_cast<std::size_t>(link)], object,
                                                                 world_.object(object).X_WO);
    max_penetration_m_[static_cast<std::size_t>(link)] =
        std::max(max_penetration_m_[static_cast<std::size_t>(link)], p.depth_m);
    link_touching[static_cast<std::size_t>(link)] = true;
  }
  for (std::size_t l = 0; l < link_touching.size(); ++l) {
    if (link_touching[l]) ++penetration_ticks_[l];
  }
  if (uncovered > 0) ++missed_ticks_;
  return uncovered;
}

}  // namespace fullarm::hil
