// The comedi I/O back-end: channel map, calibration and enable line on a Comedi board.
//
// This file is compiled twice (docs/hil.md, "The fake DAQ"): by comedi_io.cpp against comedilib
// itself (FULLARM_COMEDI_API = comedi_real_api) and by fakedaq_io.cpp against the fake DAQ's
// stand-in for the same calls (FULLARM_COMEDI_API = fakedaq_api), each time in its own
// namespace (FULLARM_COMEDI_NAMESPACE). Every board access goes through `api::`, so both builds
// run the same code. A board that advances a simulated world between reads (the fake DAQ's rig)
// hooks in through BoardClock; a real board has none.

#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "board_clock.hpp"
#include "fullarm/hil/daq_config.hpp"
#include "fullarm/hil/io_device.hpp"

namespace fullarm::hil::FULLARM_COMEDI_NAMESPACE {

namespace api = FULLARM_COMEDI_API;

class ComediBackend final : public IoDevice {
 public:
  ComediBackend(const DaqConfig& map, arm::JointSelection joints, double period_s, const IoSafetyParams& safety,
                std::string_view name, BoardClock clock)
      : IoDevice(std::move(joints), period_s, safety), map_(map), name_(name), clock_(clock) {}
  ~ComediBackend() override {
    if (calibration_ != nullptr) api::comedi_cleanup_calibration(calibration_);
    if (device_ != nullptr) api::comedi_close(device_);
  }
  [[nodiscard]] std::string_view name() const noexcept override { return name_; }

 private:
  struct Channel {
    unsigned channel = 0;
    mutable api::comedi_range range{};  // comedilib takes it by non-const pointer
    api::lsampl_t maxdata = 0;
    ChannelCalibration calibration;
    api::comedi_polynomial_t to_physical{};  // kSoftcal
  };

  [[noreturn]] void fail(const std::string& what) const {
    const int e = api::comedi_errno();
    throw DeviceError(map_.device + " (channel map " + map_.source.string() + "): " + what +
                      (e != 0 ? std::string(": ") + api::comedi_strerror(e) : std::string()));
  }

  int subdevice(int configured, int type, const char* what) {
    const int s = configured >= 0 ? configured : api::comedi_find_subdevice_by_type(device_, type, 0);
    if (s < 0) fail(std::string("the board has no ") + what + " subdevice");
    return s;
  }

  Channel channel(int sub, int range_index, const DaqChannel& c, const std::string& key) {
    const int n = api::comedi_get_n_channels(device_, static_cast<unsigned>(sub));
    if (c.channel >= n) {
      fail(key + ": channel " + std::to_string(c.channel) + " does not exist (the subdevice has " + std::to_string(n) +
           ")");
    }
    Channel ch;
    ch.channel = static_cast<unsigned>(c.channel);
    const api::comedi_range* r =
        api::comedi_get_range(device_, static_cast<unsigned>(sub), ch.channel, static_cast<unsigned>(range_index));
    if (r == nullptr) fail(key + ": range " + std::to_string(range_index) + " does not exist");
    ch.range = *r;
    ch.maxdata = api::comedi_get_maxdata(device_, static_cast<unsigned>(sub), ch.channel);
    if (ch.maxdata == 0) fail(key + ": maxdata is 0");
    ch.calibration = c.calibration;
    if (c.calibration.kind == ChannelCalibration::Kind::kSoftcal) {
      if (api::comedi_get_softcal_converter(static_cast<unsigned>(sub), ch.channel, static_cast<unsigned>(range_index),
                                            api::kToPhysical, calibration_, &ch.to_physical) < 0) {
        fail(key + ": no soft calibration for this channel and range in " + map_.softcal_file.string());
      }
    }
    return ch;
  }

  void onConfigure() override {
    if (device_ == nullptr) {
      device_ = api::comedi_open(map_.device.c_str());
      if (device_ == nullptr)
        fail("cannot open the Comedi device (is the board there, its driver loaded, its file readable?)");
    }
    api::comedi_set_global_oor_behavior(api::kOutOfRangeNan);
    if (!map_.softcal_file.empty() && calibration_ == nullptr) {
      calibration_ = api::comedi_parse_calibration_file(map_.softcal_file.c_str());
      if (calibration_ == nullptr) fail("cannot read the soft-calibration file " + map_.softcal_file.string());
    }
    ai_ = subdevice(map_.ai_subdevice, api::kSubdeviceAnalogInput, "analog-input");
    ao_ = subdevice(map_.ao_subdevice, api::kSubdeviceAnalogOutput, "analog-output");
    dio_ = subdevice(map_.dio_subdevice, api::kSubdeviceDigitalIo, "digital-I/O");
    pots_.clear();
    cells_.clear();
    valves_.clear();
    pressures_a_.clear();
    pressures_b_.clear();
    for (std::size_t k = 0; k < map_.joints.size(); ++k) {
      const DaqJoint& j = map_.joints[k];
      const std::string key = "joints[" + std::to_string(k) + "] (" + j.name + ")";
      pots_.push_back(channel(ai_, map_.ai_range, j.potentiometer, key + ".potentiometer"));
      cells_.push_back(channel(ai_, map_.ai_range, j.load_cell, key + ".load_cell"));
      valves_.push_back(channel(ao_, map_.ao_range, j.valve, key + ".valve"));
      // A joint without transducers keeps a default entry, never read.
      pressures_a_.push_back(j.hasPressures() ? channel(ai_, map_.ai_range, j.pressure_a, key + ".pressure_a")
                                              : Channel{});
      pressures_b_.push_back(j.hasPressures() ? channel(ai_, map_.ai_range, j.pressure_b, key + ".pressure_b")
                                              : Channel{});
    }
    if (map_.enable_channel >= api::comedi_get_n_channels(device_, static_cast<unsigned>(dio_))) {
      fail("board.enable_channel " + std::to_string(map_.enable_channel) +
           " does not exist on the digital-I/O subdevice");
    }
    if (api::comedi_dio_config(device_, static_cast<unsigned>(dio_), static_cast<unsigned>(map_.enable_channel),
                               api::kDigitalOutput) < 0) {
      fail("cannot configure the enable line as an output");
    }
  }

  double physical(const Channel& ch, api::lsampl_t code) const noexcept {
    // Comedi reports a code at a range end as out of range (NaN, COMEDI_OOR_NAN).
    const double volts = api::comedi_to_phys(code, &ch.range, ch.maxdata);
    if (std::isnan(volts)) return volts;
    switch (ch.calibration.kind) {
      case ChannelCalibration::Kind::kCounts:
        return (static_cast<double>(code) + ch.calibration.offset_counts) * ch.calibration.slope_per_count +
               ch.calibration.offset;
      case ChannelCalibration::Kind::kLinear:
        return ch.calibration.scale * volts + ch.calibration.offset;
      case ChannelCalibration::Kind::kSoftcal:
        return ch.calibration.scale * api::comedi_to_physical(code, &ch.to_physical) + ch.calibration.offset;
    }
    return std::numeric_limits<double>::quiet_NaN();
  }

  /// One conversion of an analog input; false when comedilib fails. @rt
  bool readCode(const Channel& ch, api::lsampl_t& code) const noexcept {
    return api::comedi_data_read(device_, static_cast<unsigned>(ai_), ch.channel, static_cast<unsigned>(map_.ai_range),
                                 api::kArefGround, &code) >= 0;
  }

  core::RtStatus onRead(JointSample& sample) noexcept override {
    if (clock_.before_read != nullptr) {
      const core::RtStatus s = clock_.before_read(clock_.context);
      if (!s.ok()) return s;
    }
    const int n = static_cast<int>(pots_.size());
    sample.q_rad.resize(n);
    sample.tau_load_cell_nm.resize(n);
    sample.p_a_pa.setZero(n);
    sample.p_b_pa.setZero(n);
    sample.out_of_range_mask = 0;
    sample.pressure_mask = 0;
    timespec now{};
    clock_gettime(CLOCK_MONOTONIC, &now);
    sample.t_s = static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
    for (int k = 0; k < n; ++k) {
      api::lsampl_t q_code = 0;
      api::lsampl_t tau_code = 0;
      const std::size_t i = static_cast<std::size_t>(k);
      if (!readCode(pots_[i], q_code) || !readCode(cells_[i], tau_code)) {
        return core::RtStatus::fault(core::RtCode::kBadInput, kFaultDeviceRead, "comedi_data_read failed");
      }
      sample.q_rad[k] = physical(pots_[i], q_code);
      sample.tau_load_cell_nm[k] = physical(cells_[i], tau_code);
      if (std::isnan(sample.q_rad[k]) || std::isnan(sample.tau_load_cell_nm[k])) sample.out_of_range_mask |= 1u << k;
      if (!map_.joints[i].hasPressures()) continue;
      // The chamber pressures: a code at a range end reads NaN, which no controller uses and
      // which does not flag the joint out of range; an identification experiment stops on it.
      api::lsampl_t pa_code = 0;
      api::lsampl_t pb_code = 0;
      if (!readCode(pressures_a_[i], pa_code) || !readCode(pressures_b_[i], pb_code)) {
        return core::RtStatus::fault(core::RtCode::kBadInput, kFaultDeviceRead, "comedi_data_read failed");
      }
      sample.p_a_pa[k] = physical(pressures_a_[i], pa_code);
      sample.p_b_pa[k] = physical(pressures_b_[i], pb_code);
      sample.pressure_mask |= 1u << k;
    }
    return {};
  }

  core::RtStatus onWrite(const IoVector& valve_v, bool toggle_enable) noexcept override {
    for (std::size_t k = 0; k < valves_.size(); ++k) {
      const Channel& ch = valves_[k];
      const double v = k < static_cast<std::size_t>(valve_v.size()) ? valve_v[static_cast<Eigen::Index>(k)] : 0.0;
      const api::lsampl_t code =
          api::comedi_from_phys(physicalToChannelVolts(ch.calibration, v), &ch.range, ch.maxdata);
      if (api::comedi_data_write(device_, static_cast<unsigned>(ao_), ch.channel, static_cast<unsigned>(map_.ao_range),
                                 api::kArefGround, code) < 0) {
        return core::RtStatus::fault(core::RtCode::kBadState, kFaultDeviceWrite, "comedi_data_write failed");
      }
    }
    // The heartbeat: the enable line changes level at every write while active; otherwise it
    // stays, and the hardware watchdog drops the amplifier enable.
    if (toggle_enable) {
      enable_level_ = !enable_level_;
      if (api::comedi_dio_write(device_, static_cast<unsigned>(dio_), static_cast<unsigned>(map_.enable_channel),
                                enable_level_ ? 1u : 0u) < 0) {
        return core::RtStatus::fault(core::RtCode::kBadState, kFaultDeviceWrite, "comedi_dio_write failed");
      }
    }
    return {};
  }

  const DaqConfig& map_;
  std::string name_;
  BoardClock clock_;
  api::comedi_t* device_ = nullptr;
  api::comedi_calibration_t* calibration_ = nullptr;
  int ai_ = -1;
  int ao_ = -1;
  int dio_ = -1;
  std::vector<Channel> pots_, cells_, valves_, pressures_a_, pressures_b_;
  bool enable_level_ = false;
};

/// The channel map's joints in `model`.
inline arm::JointSelection mapJoints(const DaqConfig& map, const arm::ArmModel& model) {
  std::vector<int> indices;
  for (const DaqJoint& j : map.joints) indices.push_back(model.jointIndex(j.name));
  return arm::JointSelection(model.numJoints(), indices);
}

}  // namespace fullarm::hil::FULLARM_COMEDI_NAMESPACE
