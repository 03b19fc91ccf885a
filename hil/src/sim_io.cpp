#include "fullarm/hil/sim_io.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

#include "fullarm/arm/sensors.hpp"
#include "fullarm/core/config_error.hpp"

namespace fullarm::hil {

void checkChannelMapFitsArm(const DaqConfig& map, const SimulatedArm& arm, std::string_view who) {
  const auto fail = [&](const std::string& key, const std::string& what) {
    throw core::ConfigError(map.source, key, std::string(who) + ": " + what);
  };
  if (static_cast<int>(map.joints.size()) != arm.numJoints()) {
    fail("joints", "the map lists " + std::to_string(map.joints.size()) + " joints, the plant has " +
                       std::to_string(arm.numJoints()));
  }
  for (int k = 0; k < arm.numJoints(); ++k) {
    const DaqJoint& j = map.joints[static_cast<std::size_t>(k)];
    // The key in the map's file: a caller may have kept only some of its joints.
    const std::string key = "joints[" + std::to_string(j.file_index >= 0 ? j.file_index : k) + "]";
    const std::string& expected = arm.model().joints[static_cast<std::size_t>(arm.joints().modelIndex(k))].name;
    if (j.name != expected) fail(key + ".name", "the map's joint is " + j.name + ", the plant's is " + expected);
    if ((j.pressure_a.channel >= 0) != (j.pressure_b.channel >= 0)) {
      fail(key + (j.pressure_a.channel >= 0 ? ".pressure_b" : ".pressure_a"),
           "expected the pressure channels of both chambers of " + j.name + " or of neither");
    }
    if (j.hasPressures() && arm.plant().joint(k).sensor_noise.pressure_full_scale_pa <= 0.0) {
      fail(key + ".pressure_a", "pressure channels for " + j.name +
                                    ", whose plant joint has no chamber pressure transducers (expected "
                                    "sensors.pressure_full_scale_pa and its companions in the plant file, or no "
                                    "pressure channels)");
    }
  }
}

SimIoDevice::SimIoDevice(SimulatedArm& arm, const SimIoOptions& options, const IoSafetyParams& safety)
    : IoDevice(arm.joints(), arm.period(), safety), arm_(arm), options_(options) {
  held_v_ = IoVector::Zero(arm.numJoints());
  if (options.converters != nullptr) checkChannelMapFitsArm(*options.converters, arm, "sim I/O");
}

void SimIoDevice::onConfigure() {
  arm_.reset();
  held_v_.setZero();
}

core::RtStatus SimIoDevice::onRead(JointSample& sample) noexcept {
  const core::RtStatus s = arm_.advance(held_v_);
  const int n = arm_.numJoints();
  sample.q_rad.resize(n);
  sample.tau_load_cell_nm.resize(n);
  sample.p_a_pa.setZero(n);
  sample.p_b_pa.setZero(n);
  sample.pressure_mask = 0;  // also when a plant node calls this directly
  sample.out_of_range_mask = 0;
  sample.t_s = arm_.readingTime();
  for (int k = 0; k < n; ++k) {
    const plant::JointMeasurement& m = arm_.reading(k);
    if (options_.converters != nullptr) {
      const DaqJoint& map = options_.converters->joints[static_cast<std::size_t>(k)];
      const ConverterRange& range = options_.converters->fake_ai;
      sample.q_rad[k] = channelToPhysical(map.potentiometer.calibration, static_cast<std::uint32_t>(m.q_counts), range);
      sample.tau_load_cell_nm[k] =
          channelToPhysical(map.load_cell.calibration, static_cast<std::uint32_t>(m.tau_counts), range);
    } else {
      // The DTS ADC: a code at either end of the 12-bit range is a saturated, invalid reading.
      const auto at_end = [](int code, int bits) { return code <= 0 || code >= arm::maxCode(bits); };
      const plant::JointParams& p = arm_.plant().joint(k);
      sample.q_rad[k] = at_end(m.q_counts, p.potentiometer.bits) ? std::numeric_limits<double>::quiet_NaN() : m.q_rad;
      sample.tau_load_cell_nm[k] =
          at_end(m.tau_counts, p.torque_sensor.bits) ? std::numeric_limits<double>::quiet_NaN() : m.tau_nm;
    }
    if (std::isnan(sample.q_rad[k]) || std::isnan(sample.tau_load_cell_nm[k])) sample.out_of_range_mask |= 1u << k;
    if (!m.pressures) continue;
    if (options_.converters == nullptr) {
      sample.p_a_pa[k] = m.p_a_pa;
      sample.p_b_pa[k] = m.p_b_pa;
      sample.pressure_mask |= 1u << k;
    } else if (const DaqJoint& map = options_.converters->joints[static_cast<std::size_t>(k)]; map.hasPressures()) {
      // Through the board's converter, as the fake DAQ reads them.
      const ConverterRange& range = options_.converters->fake_ai;
      sample.p_a_pa[k] = channelToPhysical(map.pressure_a.calibration,
                                           physicalToInputCode(map.pressure_a.calibration, m.p_a_pa, range), range);
      sample.p_b_pa[k] = channelToPhysical(map.pressure_b.calibration,
                                           physicalToInputCode(map.pressure_b.calibration, m.p_b_pa, range), range);
      sample.pressure_mask |= 1u << k;
    }
  }
  return s;
}

core::RtStatus SimIoDevice::onWrite(const IoVector& valve_v, bool toggle_enable) noexcept {
  // The valve amplifiers are enabled only by a write that beats the enable line; otherwise
  // their output is exactly 0 V (the DAC's code for 0 V is half an LSB off).
  if (!toggle_enable) {
    held_v_.setZero();
    return {};
  }
  for (int k = 0; k < held_v_.size(); ++k) {
    if (options_.converters != nullptr) {
      const DaqJoint& map = options_.converters->joints[static_cast<std::size_t>(k)];
      const ConverterRange& range = options_.converters->fake_ao;
      const std::uint32_t code = voltsToCode(physicalToChannelVolts(map.valve.calibration, valve_v[k]), range);
      held_v_[k] = codeToVolts(code, range, false);
    } else {
      held_v_[k] = codeToVolts(voltsToCode(valve_v[k], options_.dac), options_.dac, false);
    }
  }
  return {};
}

}  // namespace fullarm::hil
