#pragma once
/// @file
/// SimulatedArm: the simulated DTS behind the simulated I/O back-ends (`sim` and the fake DAQ):
/// the hydraulic ArmPlant of fullarm::plant with its sensors as the DTS reads them (12-bit
/// potentiometers and load cells), a simulated user pushing on it, and the I/O latency: the
/// readings a device gets are `latency_samples` control periods old.

#include <Eigen/Core>
#include <array>
#include <memory>

#include "fullarm/arm/arm_data.hpp"
#include "fullarm/arm/arm_model.hpp"
#include "fullarm/core/rt_status.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/plant/arm_plant.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::hil {

/// A simulated person strapped into the arm. The study's virtual technician and the scripted
/// user (scripted_user.hpp) implement it.
class SimulatedUser {
 public:
  virtual ~SimulatedUser() = default;
  /// The torques the user applies over the next control period [N m], a configuration vector
  /// (model order, size model.numJoints()), from the arm's true state at the period's start.
  /// @param fk forward kinematics of the true configuration (already computed)
  /// @rt
  virtual void userTorques(double t_s, const arm::ArmData& fk, const Eigen::VectorXd& qd_radps,
                           Eigen::VectorXd& tau_user_nm) noexcept = 0;
};

/// Largest I/O latency of the simulated back-ends [control periods].
inline constexpr int kMaxLatencySamples = 15;

/// The simulated DTS. Its joints are the plant's active joints (the plant file's joints).
class SimulatedArm {
 public:
  /// @param posture initial configuration of every model joint [rad]
  /// @param latency_samples readings are this many periods old (0 .. kMaxLatencySamples)
  /// @throws core::ConfigError from the plant, std::invalid_argument for a bad latency
  SimulatedArm(const arm::ArmModel& model, const plant::PlantConfig& plant_config, const Eigen::VectorXd& posture,
               double period_s, int latency_samples);
  ~SimulatedArm();
  SimulatedArm(const SimulatedArm&) = delete;
  SimulatedArm& operator=(const SimulatedArm&) = delete;

  /// The user who pushes on the arm (not owned; nullptr: nobody).
  void setUser(SimulatedUser* user) noexcept { user_ = user; }
  /// Back to the initial posture at rest, time 0, the sensors' and the latency line's history
  /// filled with the initial reading.
  void reset() noexcept;
  /// One control period with the valve voltages `valve_v` (plant order) held: the user's
  /// torques from the state at the start, the plant step, the sensors at the end.
  /// Allocation-free, unbounded time (the plant's adaptive integrator).
  core::RtStatus advance(const IoVector& valve_v) noexcept;

  /// The reading of joint k the devices get now (latency_samples periods old).
  [[nodiscard]] const plant::JointMeasurement& reading(int k) const noexcept;
  /// The plant time of the reading the devices get [s].
  [[nodiscard]] double readingTime() const noexcept;
  /// Plant time [s].
  [[nodiscard]] double time() const noexcept { return plant_->time(); }
  [[nodiscard]] int numJoints() const noexcept { return plant_->numJoints(); }
  [[nodiscard]] const arm::JointSelection& joints() const noexcept { return plant_->selection(); }
  [[nodiscard]] double period() const noexcept { return period_s_; }
  [[nodiscard]] int latencySamples() const noexcept { return latency_; }
  [[nodiscard]] const plant::ArmPlant& plant() const noexcept { return *plant_; }
  /// True configuration (model order) and velocities at the current plant time.
  [[nodiscard]] const Eigen::VectorXd& trueConfiguration() const noexcept { return q_true_; }
  [[nodiscard]] const Eigen::VectorXd& trueVelocity() const noexcept { return qd_true_; }
  /// The user's torques of the last period [N m], configuration vector.
  [[nodiscard]] const Eigen::VectorXd& userTorques() const noexcept { return tau_user_; }
  [[nodiscard]] const arm::ArmModel& model() const noexcept { return model_; }

 private:
  void refreshTrueState() noexcept;

  const arm::ArmModel& model_;
  double period_s_;
  int latency_;
  std::unique_ptr<plant::ArmPlant> plant_;
  SimulatedUser* user_ = nullptr;
  arm::ArmData fk_;
  Eigen::VectorXd posture_;
  Eigen::VectorXd q_true_, qd_true_, tau_user_;
  plant::PlantCommand command_;
  // Ring of the last readings: history_[(head_ - i) mod size] is i periods old.
  struct Reading {
    double t_s = 0.0;
    std::array<plant::JointMeasurement, plant::kMaxPlantJoints> joints{};
  };
  std::array<Reading, kMaxLatencySamples + 1> history_{};
  int head_ = 0;
};

}  // namespace fullarm::hil
