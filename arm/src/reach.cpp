#include "fullarm/arm/reach.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/kinematics.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::arm {
namespace {

// Stream key of the reach draws (posture k is sample k of this stream).
constexpr int kReachStream = core::nameSlot("arm.reach");

}  // namespace

ReachSample sampleReach(const ArmModel& model, int samples, std::uint64_t seed) {
  if (samples < 0) throw std::invalid_argument("sampleReach: samples = " + std::to_string(samples) + " is negative");
  ReachSample r;
  ArmData data(model);
  // The first joint's origin does not move with any joint angle: the default posture places it.
  computeForwardKinematics(model, data, model.defaultPosture());
  r.shoulder_W = data.o_W[0];
  Eigen::VectorXd q(model.numJoints());
  r.hand_W.reserve(static_cast<std::size_t>(samples));
  for (int k = 0; k < samples; ++k) {
    core::RandomStream draw(seed, kReachStream, static_cast<std::uint64_t>(k));
    for (int i = 0; i < model.numJoints(); ++i) {
      const JointLimits& lim = model.joints[static_cast<std::size_t>(i)].limits;
      q[i] = draw.uniform(lim.min_rad, lim.max_rad);
    }
    computeForwardKinematics(model, data, q);
    const Eigen::Vector3d p = data.X_WT.translation();
    r.hand_W.push_back(p);
    r.reach_m = std::max(r.reach_m, (p - r.shoulder_W).norm());
  }
  return r;
}

}  // namespace fullarm::arm
