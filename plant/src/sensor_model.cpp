#include "fullarm/plant/sensor_model.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "fullarm/arm/sensors.hpp"
#include "fullarm/core/random.hpp"

namespace fullarm::plant {
namespace {

std::uint64_t rotl(std::uint64_t x, int k) noexcept {
  return (x << k) | (x >> (64 - k));
}

}  // namespace

void GaussianNoise::reseed(std::uint64_t seed) noexcept {
  std::uint64_t x = seed;
  for (std::uint64_t& s : s_) s = core::splitMix64(x);
  has_spare_ = false;
}

std::uint64_t GaussianNoise::nextBits() noexcept {
  // xoshiro256** (Blackman and Vigna, 2018).
  const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
  const std::uint64_t t = s_[1] << 17;
  s_[2] ^= s_[0];
  s_[3] ^= s_[1];
  s_[1] ^= s_[2];
  s_[0] ^= s_[3];
  s_[2] ^= t;
  s_[3] = rotl(s_[3], 45);
  return result;
}

double GaussianNoise::nextUniform() noexcept {
  return (static_cast<double>(nextBits() >> 11) + 1.0) * 0x1.0p-53;
}

double GaussianNoise::next() noexcept {
  if (has_spare_) {
    has_spare_ = false;
    return spare_;
  }
  // Box-Muller transform.
  const double r = std::sqrt(-2.0 * std::log(nextUniform()));
  const double a = 2.0 * std::numbers::pi * nextUniform();
  spare_ = r * std::sin(a);
  has_spare_ = true;
  return r * std::cos(a);
}

JointMeasurement sampleJointSensors(const JointParams& p, JointSensorState& state, GaussianNoise& noise,
                                    double q_true_rad, double tau_true_nm, double dt_s) noexcept {
  const SensorNoiseParams& n = p.sensor_noise;
  JointMeasurement m;
  // Potentiometer: analog noise, then the 12-bit ADC and the SL count-to-angle rule.
  const double q_analog = q_true_rad + n.angle_noise_rad * noise.next();
  m.q_counts = arm::quantizeCode(arm::potentiometerCounts(p.potentiometer, q_analog), p.potentiometer.bits);
  m.q_rad = arm::potentiometerAngle(p.potentiometer, m.q_counts);
  // Load cell: bias and noise, first-order analog filter (exact ZOH discretisation), ADC.
  const double tau_analog = tau_true_nm + n.torque_bias_nm + n.torque_noise_nm * noise.next();
  if (!state.initialised || n.torque_filter_hz <= 0.0) {
    state.torque_filtered_nm = tau_analog;
    state.initialised = true;
  } else {
    const double a = std::exp(-2.0 * std::numbers::pi * n.torque_filter_hz * dt_s);
    state.torque_filtered_nm = a * state.torque_filtered_nm + (1.0 - a) * tau_analog;
  }
  m.tau_counts =
      arm::quantizeCode(arm::torqueSensorCounts(p.torque_sensor, state.torque_filtered_nm), p.torque_sensor.bits);
  m.tau_nm = arm::torqueSensorTorque(p.torque_sensor, m.tau_counts);
  return m;
}

void samplePressureSensors(const JointParams& p, GaussianNoise& noise, double p_a_true_pa, double p_b_true_pa,
                           JointMeasurement& m) noexcept {
  const SensorNoiseParams& n = p.sensor_noise;
  if (!(n.pressure_full_scale_pa > 0.0)) return;
  const double top = std::ldexp(1.0, n.pressure_bits) - 1.0;
  const double step = n.pressure_full_scale_pa / top;
  auto convert = [&](double pressure_pa) {
    const double analog = pressure_pa + n.pressure_noise_pa * noise.next();
    return std::clamp(std::round(analog / step), 0.0, top) * step;
  };
  m.p_a_pa = convert(p_a_true_pa);
  m.p_b_pa = convert(p_b_true_pa);
  m.pressures = true;
}

}  // namespace fullarm::plant
