#include "fullarm/haptics/query.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/haptics/bullet_search.hpp"

namespace fullarm::haptics {

std::unique_ptr<GlobalSearch> makeGlobalSearch(SearchKind kind, const CollisionWorld& world) {
  if (kind == SearchKind::kBullet) return std::make_unique<BulletGlobalSearch>(world);
  return std::make_unique<SnchGlobalSearch>();
}

QueryRendering::QueryRendering(const arm::ArmModel& model, RenderMode render_mode, int max_minima)
    : mode(render_mode),
      contact(model, std::max(1, max_minima)),
      tau_contact_nm(Eigen::VectorXd::Zero(model.numJoints())),
      tau_total_nm(Eigen::VectorXd::Zero(model.numJoints())) {}

bool QueryResult::fault() const noexcept {
  return std::any_of(renderings.begin(), renderings.end(), [](const QueryRendering& r) { return !r.contact.status.ok(); });
}

QueryResult renderQuery(const arm::ArmModel& model, const CollisionWorld& world, GlobalSearch& search,
                        const HapticsParams& params, const Eigen::VectorXd& q, std::span<const RenderMode> modes) {
  if (q.size() != model.numJoints()) {
    throw std::invalid_argument("renderQuery: q has " + std::to_string(q.size()) + " values, the arm " +
                                std::to_string(model.numJoints()) + " joints");
  }
  if (modes.empty()) throw std::invalid_argument("renderQuery: no rendering mode");
  QueryResult r;
  r.q_rad = q;
  r.search = std::string(search.name());
  arm::ArmData fk(model);
  arm::computeForwardKinematics(model, fk, q);
  r.X_WL = fk.X_WL;

  const auto start = std::chrono::steady_clock::now();
  search.search(world, fk, params.cutoff_m, params.prune_radius_m, r.minima);
  r.search_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();

  arm::computeGravityTorquesAtKinematics(model, fk);
  r.tau_gravity_nm = fk.tau_gravity;

  r.renderings.reserve(modes.size());
  for (const RenderMode mode : modes) {
    HapticsParams mode_params = params;
    mode_params.mode = mode;
    QueryRendering& x = r.renderings.emplace_back(model, mode, static_cast<int>(r.minima.size()));
    computeContactForces(mode_params, model, fk, r.minima, kQueryTick_s, x.contact);
    computeContactTorques(model, fk, r.minima, x.contact);
    x.tau_contact_nm = x.contact.tau_contact_nm;
    x.tau_total_nm = x.tau_contact_nm + r.tau_gravity_nm;
  }
  return r;
}

}  // namespace fullarm::haptics
