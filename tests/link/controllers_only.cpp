// A program that links fullarm::controllers alone, as a real-time node does: it loads the shipped
// arm model and gains, steps the arm controller for a few control periods with a user pushing
// on every joint, and checks that every valve command is finite, within the valve limit, not
// all zero, and that no joint faulted. Exit 0 on success, 1 with a message otherwise.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <exception>

#include <Eigen/Core>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_yaml.hpp"
#include "fullarm/arm/dynamics.hpp"
#include "fullarm/controllers/arm_controller.hpp"
#include "fullarm/controllers/gains.hpp"

namespace {

constexpr int kPeriods = 20;
constexpr double kUserPushNm = 2.0;  // the user's torque on every joint (load cell = g(q) - push)

int run() {
  using namespace fullarm;
  const arm::ArmModel model = arm::loadArmModel(arm::defaultArmModelPath());
  const controllers::GainsConfig gains = controllers::loadGainsConfig(controllers::defaultGainsConfigPath(), model);
  const controllers::ArmControllerModel controller = controllers::makeArmControllerModel(gains, model);
  const int n = controller.numJoints();
  if (n < 1) {
    std::fprintf(stderr, "no joint in %s\n", gains.source.string().c_str());
    return 1;
  }
  arm::ArmData arm_data(model);
  controllers::ArmControllerData data;
  const Eigen::VectorXd q = model.defaultPosture();
  controllers::resetArmController(controller, data, q);
  arm::computeGravityTorques(model, arm_data, q);
  Eigen::VectorXd cells(n);
  controller.selection.gather(arm_data.tau_gravity, cells);
  cells.array() -= kUserPushNm;
  const Eigen::VectorXd contact = Eigen::VectorXd::Zero(model.numJoints());
  Eigen::VectorXd valve(n);
  double largest_v = 0.0;
  for (int k = 0; k < kPeriods; ++k) {
    controllers::stepArmController(controller, data, q, arm_data.tau_gravity, contact, cells, valve);
    if (!data.status.ok()) {
      std::fprintf(stderr, "period %d: controller fault %s (bits 0x%x)\n", k, data.status.message,
                   static_cast<unsigned>(data.status.faults));
      return 1;
    }
    for (int i = 0; i < n; ++i) {
      const double limit = gains.joints[static_cast<std::size_t>(i)].valve_limit_v;
      if (!std::isfinite(valve[i]) || std::abs(valve[i]) > limit) {
        std::fprintf(stderr, "period %d, joint %s: valve command %g V (limit %g V)\n", k,
                     gains.joints[static_cast<std::size_t>(i)].name.c_str(), valve[i], limit);
        return 1;
      }
      largest_v = std::max(largest_v, std::abs(valve[i]));
    }
  }
  // The user pushes: the admittance law must move the valves.
  if (!(largest_v > 0.0)) {
    std::fprintf(stderr, "every valve command stayed 0 V under a %g N m push\n", kUserPushNm);
    return 1;
  }
  std::printf("controllers alone: %d joints, %d periods, largest valve command %.4f V\n", n, kPeriods, largest_v);
  return 0;
}

}  // namespace

int main() {
  try {
    return run();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
