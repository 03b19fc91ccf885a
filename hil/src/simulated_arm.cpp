#include "fullarm/hil/simulated_arm.hpp"

#include <stdexcept>
#include <string>

#include "fullarm/arm/kinematics.hpp"

namespace fullarm::hil {

SimulatedArm::SimulatedArm(const arm::ArmModel& model, const plant::PlantConfig& plant_config,
                           const Eigen::VectorXd& posture, double period_s, int latency_samples)
    : model_(model),
      period_s_(period_s),
      latency_(latency_samples),
      plant_(std::make_unique<plant::ArmPlant>()),
      fk_(model),
      posture_(posture) {
  if (latency_samples < 0 || latency_samples > kMaxLatencySamples) {
    throw std::invalid_argument("SimulatedArm: latency_samples " + std::to_string(latency_samples) +
                                " outside 0 .. " + std::to_string(kMaxLatencySamples));
  }
  if (posture.size() != model.numJoints()) throw std::invalid_argument("SimulatedArm: posture of the wrong size");
  plant::UserArmParams no_cuff;  // the user pushes through userTorques(), not the plant's cuff spring
  plant_->configure(model, plant_config.joints, posture, no_cuff, plant_config.solver, plant_config.seed);
  q_true_ = posture;
  qd_true_ = Eigen::VectorXd::Zero(model.numJoints());
  tau_user_ = Eigen::VectorXd::Zero(model.numJoints());
  command_ = plant::PlantCommand::zero(plant_->numJoints());
  reset();
}

SimulatedArm::~SimulatedArm() = default;

void SimulatedArm::refreshTrueState() noexcept {
  q_true_ = posture_;
  qd_true_.setZero();
  for (int k = 0; k < plant_->numJoints(); ++k) {
    const plant::JointState s = plant_->state(k);
    q_true_[plant_->modelIndex(k)] = s.q_rad;
    qd_true_[plant_->modelIndex(k)] = s.qd_radps;
  }
}

void SimulatedArm::reset() noexcept {
  plant_->reset();
  refreshTrueState();
  tau_user_.setZero();
  // The sensors before the first period read the initial state (the plant samples them at reset).
  Reading first;
  first.t_s = 0.0;
  for (int k = 0; k < plant_->numJoints(); ++k) first.joints[static_cast<std::size_t>(k)] = plant_->measurement(k);
  history_.fill(first);
  head_ = 0;
}

core::RtStatus SimulatedArm::advance(const IoVector& valve_v) noexcept {
  const int n = plant_->numJoints();
  tau_user_.setZero();
  if (user_ != nullptr) {
    arm::computeForwardKinematics(model_, fk_, q_true_);
    user_->userTorques(plant_->time(), fk_, qd_true_, tau_user_);
  }
  for (int k = 0; k < n; ++k) {
    command_.command[k] = k < valve_v.size() ? valve_v[k] : 0.0;
    command_.tau_user_nm[k] = tau_user_[plant_->modelIndex(k)];
    command_.tau_contact_nm[k] = 0.0;  // the virtual environment acts only through the valves
  }
  const core::RtStatus s = plant_->step(period_s_, command_);
  refreshTrueState();
  head_ = (head_ + 1) % static_cast<int>(history_.size());
  Reading& r = history_[static_cast<std::size_t>(head_)];
  r.t_s = plant_->time();
  for (int k = 0; k < n; ++k) r.joints[static_cast<std::size_t>(k)] = plant_->measurement(k);
  return s;
}

const plant::JointMeasurement& SimulatedArm::reading(int k) const noexcept {
  const int size = static_cast<int>(history_.size());
  const int index = ((head_ - latency_) % size + size) % size;
  return history_[static_cast<std::size_t>(index)].joints[static_cast<std::size_t>(k)];
}

double SimulatedArm::readingTime() const noexcept {
  const int size = static_cast<int>(history_.size());
  const int index = ((head_ - latency_) % size + size) % size;
  return history_[static_cast<std::size_t>(index)].t_s;
}

}  // namespace fullarm::hil
