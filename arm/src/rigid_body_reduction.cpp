#include "fullarm/arm/rigid_body_reduction.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <stdexcept>
#include <string>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"

namespace fullarm::arm {
namespace {

// |c|^2 I - c c^T: the inertia of a unit point mass at c about the origin.
Eigen::Matrix3d skewSquare(const Eigen::Vector3d& c) {
  return c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose();
}

std::vector<int> owners(const ArmModel& model, const std::vector<int>& active) {
  // owner[l]: body whose joint is the nearest active ancestor-or-self of link l, or -1.
  std::vector<int> owner(static_cast<std::size_t>(model.numJoints()), -1);
  for (int l = 0; l < model.numJoints(); ++l) {
    for (int j = l; j >= 0; j = model.joints[static_cast<std::size_t>(j)].parent) {
      const auto it = std::find(active.begin(), active.end(), j);
      if (it != active.end()) {
        owner[static_cast<std::size_t>(l)] = static_cast<int>(it - active.begin());
        break;
      }
    }
  }
  return owner;
}

void checkActive(const ArmModel& model, const std::vector<int>& active, const Eigen::VectorXd& posture) {
  if (active.empty() || static_cast<int>(active.size()) > kMaxBodies) {
    throw std::invalid_argument("reduceArmModel: expected 1 to " + std::to_string(kMaxBodies) + " active joints");
  }
  if (posture.size() != model.numJoints()) {
    throw std::invalid_argument("reduceArmModel: posture has " + std::to_string(posture.size()) + " angles, expected " +
                                std::to_string(model.numJoints()));
  }
  for (std::size_t k = 0; k < active.size(); ++k) {
    if (active[k] < 0 || active[k] >= model.numJoints()) {
      throw std::invalid_argument("reduceArmModel: active joint index " + std::to_string(active[k]) + " out of range");
    }
    if (std::find(active.begin(), active.begin() + static_cast<std::ptrdiff_t>(k), active[k]) !=
        active.begin() + static_cast<std::ptrdiff_t>(k)) {
      throw std::invalid_argument("reduceArmModel: active joint " + std::to_string(active[k]) + " listed twice");
    }
  }
}

// Body k's frame in the world at the posture, with its own joint at q = 0.
Eigen::Isometry3d bodyFrameAtZero(const ArmData& d, const std::vector<int>& active, const Eigen::VectorXd& posture,
                                  int k) {
  const int i = active[static_cast<std::size_t>(k)];
  return d.X_WL[static_cast<std::size_t>(i)] * Eigen::AngleAxisd(-posture[i], Eigen::Vector3d::UnitZ());
}

}  // namespace

// R1: locked links merged into their active ancestor (parallel-axis theorem) (reports/equations.md).
RigidBodyModel reduceArmModel(const ArmModel& model, const std::vector<int>& active, const Eigen::VectorXd& posture) {
  checkActive(model, active, posture);
  ArmData d(model);
  computeForwardKinematics(model, d, posture);
  const std::vector<int> owner = owners(model, active);
  RigidBodyModel r;
  r.tree.n = static_cast<int>(active.size());
  r.gravity_W_mps2 = model.gravity_W_mps2;
  for (int k = 0; k < r.tree.n; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    const int i = active[kk];
    const int model_parent = model.joints[static_cast<std::size_t>(i)].parent;
    const int p = model_parent < 0 ? -1 : owner[static_cast<std::size_t>(model_parent)];
    r.tree.parent[kk] = p;
    // X_PB0 = X_WP^-1 X_WB0, both at the posture (the locked joints in between are rigid).
    const Eigen::Isometry3d X_WB0 = bodyFrameAtZero(d, active, posture, k);
    const Eigen::Isometry3d X_PB0 =
        p < 0 ? X_WB0
              : Eigen::Isometry3d(d.X_WL[static_cast<std::size_t>(active[static_cast<std::size_t>(p)])].inverse() *
                                  X_WB0);
    r.rotation0[kk] = X_PB0.linear();
    r.translation0_m[kk] = X_PB0.translation();
    // Merge every link the body carries rigidly: mass, first moment and inertia about the
    // body origin in the body frame (at the posture), then about the merged centre of mass.
    const Eigen::Isometry3d X_BW = d.X_WL[static_cast<std::size_t>(i)].inverse();
    double m = 0.0;
    Eigen::Vector3d first = Eigen::Vector3d::Zero();
    Eigen::Matrix3d inertia_B = Eigen::Matrix3d::Zero();
    for (int l = 0; l < model.numJoints(); ++l) {
      if (owner[static_cast<std::size_t>(l)] != k) continue;
      const LinkInertial& in = model.joints[static_cast<std::size_t>(l)].inertial;
      const Eigen::Isometry3d X_BL = X_BW * d.X_WL[static_cast<std::size_t>(l)];
      const Eigen::Vector3d c = X_BL * in.com_m;
      const Eigen::Matrix3d R = X_BL.linear();
      m += in.mass_kg;
      first += in.mass_kg * c;
      inertia_B += R * in.inertia_com_kgm2 * R.transpose() + in.mass_kg * skewSquare(c);
    }
    r.mass_kg[kk] = m;
    r.com_m[kk] = m > 0.0 ? Eigen::Vector3d(first / m) : Eigen::Vector3d::Zero();
    r.inertia_com_kgm2[kk] = inertia_B - m * skewSquare(r.com_m[kk]);
  }
  // Topological order: the arm model lists parents before children.
  std::vector<int> order(static_cast<std::size_t>(r.tree.n));
  for (int k = 0; k < r.tree.n; ++k) order[static_cast<std::size_t>(k)] = k;
  std::sort(order.begin(), order.end(), [&active](int a, int b) {
    return active[static_cast<std::size_t>(a)] < active[static_cast<std::size_t>(b)];
  });
  std::copy(order.begin(), order.end(), r.tree.order.begin());
  for (int k = 0; k < r.tree.n; ++k) {
    for (int b = 0; b < r.tree.n; ++b)
      r.tree.supports[static_cast<std::size_t>(k)][static_cast<std::size_t>(b)] =
          jointMovesLink(model, active[static_cast<std::size_t>(k)], active[static_cast<std::size_t>(b)]);
  }
  return r;
}

BodyPoint reducePoint(const ArmModel& model, const std::vector<int>& active, const Eigen::VectorXd& posture, int link,
                      const Eigen::Vector3d& p_L) {
  checkActive(model, active, posture);
  if (link < 0 || link >= model.numJoints())
    throw std::invalid_argument("reducePoint: link index " + std::to_string(link) + " out of range");
  ArmData d(model);
  computeForwardKinematics(model, d, posture);
  BodyPoint point;
  point.body = owners(model, active)[static_cast<std::size_t>(link)];
  const Eigen::Vector3d p_W = pointInWorld(d, link, p_L);
  point.p_B = point.body < 0
                  ? p_W
                  : Eigen::Vector3d(
                        d.X_WL[static_cast<std::size_t>(active[static_cast<std::size_t>(point.body)])].inverse() * p_W);
  return point;
}

}  // namespace fullarm::arm
