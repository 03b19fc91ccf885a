#pragma once
/// @file
/// Potentiometer and load-cell models as the DTS reads them (docs/dts-reference.md
/// section 6): analog noise and bias, a first-order analog filter on the load cell, then a
/// 12-bit ADC with the calibration of the arm model. Seeded, deterministic noise.

#include <cstdint>

#include "fullarm/plant/joint_params.hpp"

namespace fullarm::plant {

/// Deterministic Gaussian noise: xoshiro256** with a Box-Muller transform (same sequence on
/// every platform for a given seed). @rt after construction.
class GaussianNoise {
 public:
  explicit GaussianNoise(std::uint64_t seed = 1) noexcept { reseed(seed); }
  void reseed(std::uint64_t seed) noexcept;
  /// Standard normal sample. @rt
  [[nodiscard]] double next() noexcept;

 private:
  [[nodiscard]] std::uint64_t nextBits() noexcept;
  [[nodiscard]] double nextUniform() noexcept;  // in (0, 1]
  std::uint64_t s_[4] = {};
  double spare_ = 0.0;
  bool has_spare_ = false;
};

/// One joint's sensor chain state (filter memory).
struct JointSensorState {
  double torque_filtered_nm = 0.0;
  bool initialised = false;
};

/// What the DTS reads for one joint in one control period.
struct JointMeasurement {
  double q_rad = 0.0;   ///< potentiometer angle after the ADC
  double tau_nm = 0.0;  ///< load-cell torque after the filter and the ADC
  int q_counts = 0;     ///< ADC code of the potentiometer
  int tau_counts = 0;   ///< ADC code of the load cell
  /// Chamber pressures [Pa, gauge] after their transducers' ADC (SensorNoiseParams; both 0 and
  /// `pressures` false for a joint without pressure transducers).
  double p_a_pa = 0.0;
  double p_b_pa = 0.0;
  bool pressures = false;
};

/// Samples both sensors of one joint at the end of a control period of `dt_s`.
/// The load-cell filter is the exact zero-order-hold discretisation of 1/(tau s + 1).
/// @param q_true_rad true joint angle; @param tau_true_nm true transmitted torque (load cell)
/// @rt
JointMeasurement sampleJointSensors(const JointParams& p, JointSensorState& state, GaussianNoise& noise,
                                    double q_true_rad, double tau_true_nm, double dt_s) noexcept;

/// Samples a joint's chamber pressure transducers into `m` (p_a_pa, p_b_pa, pressures = true):
/// noise of SensorNoiseParams::pressure_noise_pa, then an ADC of pressure_bits over
/// [0, pressure_full_scale_pa] that saturates at both ends. No effect for a joint without them
/// (full scale 0). Their noise comes from its own stream, so adding transducers leaves the
/// angle and load-cell readings of a seeded run unchanged.
/// @rt
void samplePressureSensors(const JointParams& p, GaussianNoise& noise, double p_a_true_pa, double p_b_true_pa,
                           JointMeasurement& m) noexcept;

}  // namespace fullarm::plant
