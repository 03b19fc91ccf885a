#include "fullarm/accessibility/brace_search.hpp"

#include <Eigen/SVD>
#include <array>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/random.hpp"
#include "fullarm/haptics/query.hpp"

namespace fullarm::accessibility {
namespace {

/// Everything one search needs between its steps.
struct Search {
  const arm::ArmModel& model;
  const HumanArm& human;
  const haptics::CollisionWorld& world;
  haptics::GlobalSearch& global;
  const haptics::HapticsParams& params;
  const Eigen::Vector3d push_W;
  const BraceSearchOptions& options;
  PushOptions push_options;
  arm::ArmData fk;
  Eigen::Isometry3d X_WT_target;
  int n_arm;
  Eigen::VectorXd lower;
  Eigen::VectorXd upper;
  BraceSearchResult result;

  /// Hand pose Jacobian (linear and angular rows) over the arm joints at fk.
  Eigen::MatrixXd handJacobian() {
    arm::PointJacobian J;
    arm::computePointJacobian(model, fk, model.tool_link, fk.X_WT.translation(), J);
    return J.leftCols(n_arm);
  }

  /// Hand pose error (position; orientation as a rotation vector) at fk.
  Eigen::Matrix<double, 6, 1> poseError() const {
    Eigen::Matrix<double, 6, 1> e;
    e.head<3>() = X_WT_target.translation() - fk.X_WT.translation();
    const Eigen::AngleAxisd aa(X_WT_target.linear() * fk.X_WT.linear().transpose());
    e.tail<3>() = aa.angle() * aa.axis();
    return e;
  }

  bool withinLimits(const Eigen::VectorXd& q) const {
    for (int i = 0; i < n_arm; ++i) {
      if (q[i] < lower[i] || q[i] > upper[i]) return false;
    }
    return true;
  }

  /// Pulls q back onto the hand's pose (damped least squares); false if it does not converge
  /// within the tolerances or leaves the joint range.
  bool project(Eigen::VectorXd& q) {
    constexpr int kIterations = 30;
    constexpr double kDamping = 1e-6;
    for (int it = 0; it <= kIterations; ++it) {
      arm::computeForwardKinematics(model, fk, q);
      const Eigen::Matrix<double, 6, 1> e = poseError();
      if (e.head<3>().norm() <= 0.1 * options.hand_position_tolerance_m &&
          e.tail<3>().norm() <= 0.1 * options.hand_orientation_tolerance_rad) {
        return withinLimits(q);
      }
      if (it == kIterations) break;
      const Eigen::MatrixXd J = handJacobian();
      const Eigen::MatrixXd JJt = J * J.transpose() + kDamping * Eigen::MatrixXd::Identity(6, 6);
      q.head(n_arm) += J.transpose() * JJt.ldlt().solve(e);
    }
    return false;
  }

  /// Unit basis of the self-motion (null space of the hand pose Jacobian) at q.
  Eigen::MatrixXd nullSpace(const Eigen::VectorXd& q) {
    arm::computeForwardKinematics(model, fk, q);
    const Eigen::MatrixXd J = handJacobian();
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(J, Eigen::ComputeFullV);
    const Eigen::VectorXd& sv = svd.singularValues();
    const double tol = 1e-9 * std::max(1.0, sv[0]);
    Eigen::Index rank = 0;
    while (rank < sv.size() && sv[rank] > tol) ++rank;
    return svd.matrixV().rightCols(n_arm - rank);
  }

  /// Evaluates one candidate: haptic query, contact check, the force program. Returns false
  /// when the contact is not allowed.
  bool evaluate(const Eigen::VectorXd& q, PushAnalysis& out) {
    ++result.evaluations;
    const std::array<haptics::RenderMode, 1> modes{haptics::RenderMode::kFullArm};
    const haptics::QueryResult query = haptics::renderQuery(model, world, global, params, q, modes);
    const haptics::QueryRendering& r = query.renderings.front();
    arm::computeForwardKinematics(model, fk, q);
    result.max_hand_error_m = std::max(result.max_hand_error_m, poseError().head<3>().norm());
    for (int l = 0; l < model.numJoints(); ++l) {
      if (haptics::isHandLink(model, l)) continue;
      const auto li = static_cast<std::size_t>(l);
      if (r.contact.link_force_W[li].norm() > options.contact_force_max_n ||
          r.contact.links[li].depth_m > options.penetration_max_m) {
        ++result.rejected_contact;
        return false;
      }
    }
    out = analysePush(model, human, fk, push_W, query.minima, push_options);
    return true;
  }

  void consider(const Eigen::VectorXd& q, const PushAnalysis& a) {
    if (a.braced.status != ForceStatus::kOptimal) return;
    if (!(result.best.braced.status == ForceStatus::kOptimal) || a.braced.push_n > result.best.braced.push_n) {
      result.best = a;
      result.q_best_rad = q;
    }
  }

  /// One self-motion step of joint-space length `step` along `direction` (null-space coordinates
  /// at q, sign kept continuous through `previous`), projected back onto the hand's pose.
  bool step(Eigen::VectorXd& q, const Eigen::VectorXd& coords, double step_rad, Eigen::VectorXd& previous) {
    const Eigen::MatrixXd N = nullSpace(q);
    if (N.cols() == 0) return false;
    Eigen::VectorXd c = coords.head(std::min<Eigen::Index>(coords.size(), N.cols()));
    if (c.size() < N.cols()) c.conservativeResizeLike(Eigen::VectorXd::Zero(N.cols()));
    Eigen::VectorXd dq = N * c;
    if (dq.norm() == 0.0) return false;
    dq.normalize();
    if (previous.size() == dq.size() && previous.dot(dq) < 0.0) dq = -dq;
    previous = dq;
    Eigen::VectorXd candidate = q;
    candidate.head(n_arm) += step_rad * dq;
    if (!project(candidate)) {
      ++result.rejected_limits;
      return false;
    }
    q = candidate;
    return true;
  }
};

}  // namespace

BraceSearchResult searchBracePosture(const arm::ArmModel& model, const HumanArm& human,
                                     const haptics::CollisionWorld& world, haptics::GlobalSearch& search,
                                     const haptics::HapticsParams& params, const Eigen::VectorXd& q_start,
                                     const Eigen::Vector3d& push_direction_W, const BraceSearchOptions& options) {
  if (q_start.size() != model.numJoints()) {
    throw std::invalid_argument("brace search: the start configuration has " + std::to_string(q_start.size()) +
                                " values, the arm model " + std::to_string(model.numJoints()) + " joints");
  }
  if (options.max_evaluations < 1) throw std::invalid_argument("brace search: max_evaluations must be >= 1");
  if (!(options.step_rad > 0.0)) throw std::invalid_argument("brace search: step_rad must be > 0");
  Search s{model,
           human,
           world,
           search,
           params,
           push_direction_W.normalized(),
           options,
           options.push,
           arm::ArmData(model),
           Eigen::Isometry3d::Identity(),
           model.numArmJoints(),
           model.lowerLimits(),
           model.upperLimits(),
           {}};
  s.push_options.contact_distance_m = params.force_threshold_m;
  if (!s.withinLimits(q_start))
    throw std::invalid_argument("brace search: the start configuration is outside the joint limits");
  arm::computeForwardKinematics(model, s.fk, q_start);
  s.X_WT_target = s.fk.X_WT;
  s.result.q_start_rad = q_start;
  s.result.q_best_rad = q_start;

  // The start: evaluated whatever its contact (it is where the hand reached the target).
  {
    PushAnalysis a;
    const bool allowed = s.evaluate(q_start, a);
    if (!allowed) {
      arm::computeForwardKinematics(model, s.fk, q_start);
      const std::array<haptics::RenderMode, 1> modes{haptics::RenderMode::kFullArm};
      const haptics::QueryResult query = haptics::renderQuery(model, world, search, params, q_start, modes);
      a = analysePush(model, human, s.fk, s.push_W, query.minima, s.push_options);
    }
    s.result.start = a;
    s.result.best = a;
    if (allowed) s.consider(q_start, a);
  }

  // Phase 1: sweep the self-motion from the start along each null-space direction, both ways,
  // until a joint limit, a contact that is not allowed, or half the budget.
  const int sweep_budget = std::max(1, options.max_evaluations / 2);
  const Eigen::MatrixXd N0 = s.nullSpace(q_start);
  for (Eigen::Index axis = 0; axis < N0.cols(); ++axis) {
    for (const double sign : {1.0, -1.0}) {
      Eigen::VectorXd q = q_start;
      Eigen::VectorXd previous = sign * N0.col(axis);
      Eigen::VectorXd coords = Eigen::VectorXd::Zero(N0.cols());
      coords[axis] = 1.0;
      while (s.result.evaluations < sweep_budget) {
        if (!s.step(q, coords, options.step_rad, previous)) break;
        PushAnalysis a;
        if (!s.evaluate(q, a)) break;
        s.consider(q, a);
      }
    }
  }

  // Phase 2: seeded refinement around the best posture: random self-motion steps of shrinking
  // size; a step is kept when it raises the braced push.
  // Failed steps (a joint limit, the hand off its pose) cost no evaluation; they are bounded too.
  int index = 0;
  const int max_attempts = 4 * options.max_evaluations;
  while (s.result.evaluations < options.max_evaluations && index < max_attempts) {
    core::RandomStream rng(options.seed, 0, static_cast<std::uint64_t>(index++));
    const double progress =
        static_cast<double>(s.result.evaluations - sweep_budget) / std::max(1, options.max_evaluations - sweep_budget);
    const double size = options.step_rad * (1.0 - 0.9 * progress) * rng.uniform(0.1, 1.0);
    Eigen::VectorXd coords(std::max<Eigen::Index>(N0.cols(), 1));
    for (Eigen::Index i = 0; i < coords.size(); ++i) coords[i] = rng.uniform(-1.0, 1.0);
    Eigen::VectorXd q = s.result.q_best_rad;
    Eigen::VectorXd previous;
    if (N0.cols() == 0) break;
    if (!s.step(q, coords, size, previous)) continue;
    PushAnalysis a;
    if (s.evaluate(q, a)) s.consider(q, a);
  }
  return s.result;
}

}  // namespace fullarm::accessibility
