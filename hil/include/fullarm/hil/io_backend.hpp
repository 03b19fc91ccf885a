#pragma once
/// @file
/// An I/O back-end built by name: the device and whatever stands behind it in this process (the
/// simulated DTS for sim and fakedaq, the fake board and its rig for fakedaq). `fullarm run`,
/// `fullarm identify` and `fullarm gravity` build their devices here, so every command drives
/// the same back-end the same way.

#include <Eigen/Core>
#include <filesystem>
#include <memory>
#include <string>

#include "fullarm/arm/arm_model.hpp"
#include "fullarm/arm/joint_selection.hpp"
#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/fake_daq.hpp"
#include "fullarm/hil/io_device.hpp"
#include "fullarm/hil/simulated_arm.hpp"
#include "fullarm/plant/plant_config.hpp"

namespace fullarm::hil {

/// Which I/O back-end drives the arm.
/// kLcm: remote I/O, the device's back-end in a plant node in another process (lcm_io.hpp).
enum class IoKind { kSim, kFakeDaq, kComedi, kLcm };

/// "sim", "fakedaq", "comedi" or "lcm".
[[nodiscard]] const char* ioKindName(IoKind io) noexcept;

/// How a back-end is built. The pointed-to files outlive the back-end.
struct IoBackendOptions {
  IoKind io = IoKind::kSim;
  double period_s = 1.0e-3;  ///< the control period
  int latency_samples = 1;   ///< sim, fakedaq: the simulated arm's I/O latency
  IoSafetyParams safety;     ///< the device's safety policy
  /// sim, fakedaq: the simulated DTS (its seed and integrator as given).
  const plant::PlantConfig* plant = nullptr;
  /// sim, fakedaq: the simulated arm's start posture (model order).
  Eigen::VectorXd posture;
  /// fakedaq, comedi: the channel map; sim: its converters when sim_uses_daq_converters.
  const DaqConfig* daq = nullptr;
  /// sim: read and write through the channel map's converters and calibrations.
  bool sim_uses_daq_converters = false;
  /// fakedaq: the fake board's state file (empty: in memory).
  std::filesystem::path fakedaq_state_file;
  /// lcm: the device's joints (the plant node's), its URL (empty: the default) and how long a
  /// reading may take (0: the remote device's default).
  arm::JointSelection lcm_joints;
  std::string lcm_url;
  double lcm_reply_timeout_s = 0.0;
  /// lcm: consecutive unanswered reads that mean the link is lost (0: the device's default). 1
  /// for a recording that must not repeat a reading (identification, static holds).
  int lcm_max_missed_replies = 0;
};

/// The device of one back-end and what it drives in this process.
class IoBackend {
 public:
  /// Builds the back-end (sim and fakedaq: the simulated arm at `options.posture`).
  /// @throws std::invalid_argument for a missing plant, posture or channel map; DeviceError when
  ///   the device cannot be opened (comedi without its board names the device file)
  IoBackend(const arm::ArmModel& model, const IoBackendOptions& options);
  ~IoBackend();
  IoBackend(const IoBackend&) = delete;
  IoBackend& operator=(const IoBackend&) = delete;

  [[nodiscard]] IoDevice& device() noexcept { return *device_; }
  /// The simulated arm behind sim and fakedaq (nullptr for comedi and lcm).
  [[nodiscard]] SimulatedArm* simulatedArm() noexcept { return arm_.get(); }
  /// The fake board (fakedaq only; nullptr otherwise).
  [[nodiscard]] FakeDaqBoard* fakeBoard() noexcept { return board_.get(); }
  [[nodiscard]] IoKind kind() const noexcept { return kind_; }

 private:
  IoKind kind_;
  std::unique_ptr<SimulatedArm> arm_;
  std::unique_ptr<FakeDaqBoard> board_;
  std::unique_ptr<FakeDaqRig> rig_;
  std::unique_ptr<IoDevice> device_;
};

}  // namespace fullarm::hil
