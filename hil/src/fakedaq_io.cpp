// The fake DAQ: the comedilib stand-in (fake_comedilib.hpp) on FakeDaqBoard, the rig that wires
// it to the simulated DTS, and the comedi back-end (comedi_backend.ipp) compiled against it.

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <map>
#include <mutex>
#include <new>
#include <stdexcept>

#include "fake_comedilib.hpp"
#include "fullarm/hil/fake_daq.hpp"
#include "fullarm/hil/sim_io.hpp"

#define FULLARM_COMEDI_NAMESPACE fakedaq_board
#define FULLARM_COMEDI_API ::fullarm::hil::fakedaq_api
#include "comedi_backend.ipp"

namespace fullarm::hil {

// --- the board -------------------------------------------------------------------------------

namespace {

std::mutex& registryMutex() {
  static std::mutex m;
  return m;
}
std::map<std::string, FakeDaqState*>& registry() {
  static std::map<std::string, FakeDaqState*> r;
  return r;
}

std::int64_t monotonicNs() noexcept {
  timespec t{};
  clock_gettime(CLOCK_MONOTONIC, &t);
  return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
}

}  // namespace

FakeDaqBoard::FakeDaqBoard(const DaqConfig& map, const std::filesystem::path& state_file)
    : device_(map.device), file_(state_file) {
  if (map.fake_ai_channels > kFakeDaqMaxAnalogInputs || map.fake_ao_channels > kFakeDaqMaxAnalogOutputs ||
      map.fake_dio_channels > kFakeDaqMaxDigitalLines) {
    throw DeviceError(map.source.string() + ": fake_board has more channels than the fake DAQ offers");
  }
  if (file_.empty()) {
    memory_ = std::make_unique<FakeDaqState>();
    state_ = memory_.get();
  } else {
    const int fd = ::open(file_.c_str(), O_RDWR | O_CREAT | O_TRUNC, 0644);
    if (fd < 0)
      throw std::runtime_error(file_.string() + ": cannot create the fake DAQ's state file: " + std::strerror(errno));
    mapped_bytes_ = sizeof(FakeDaqState);
    if (::ftruncate(fd, static_cast<off_t>(mapped_bytes_)) != 0) {
      ::close(fd);
      throw std::runtime_error(file_.string() + ": cannot size the fake DAQ's state file: " + std::strerror(errno));
    }
    void* p = ::mmap(nullptr, mapped_bytes_, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
    ::close(fd);
    if (p == MAP_FAILED)
      throw std::runtime_error(file_.string() + ": cannot map the fake DAQ's state: " + std::strerror(errno));
    state_ = new (p) FakeDaqState();
  }
  FakeDaqState& s = *state_;
  s.ai = map.fake_ai;
  s.ao = map.fake_ao;
  s.ai_channels = map.fake_ai_channels;
  s.ao_channels = map.fake_ao_channels;
  s.dio_channels = map.fake_dio_channels;
  s.enable_line = map.enable_channel;
  s.magic = kFakeDaqMagic;
  std::lock_guard lock(registryMutex());
  registry()[device_] = state_;
}

FakeDaqBoard::~FakeDaqBoard() {
  {
    std::lock_guard lock(registryMutex());
    const auto it = registry().find(device_);
    if (it != registry().end() && it->second == state_) registry().erase(it);
  }
  if (!file_.empty() && state_ != nullptr) ::munmap(state_, mapped_bytes_);
}

std::shared_ptr<const FakeDaqState> FakeDaqBoard::inspect(const std::filesystem::path& state_file) {
  const int fd = ::open(state_file.c_str(), O_RDONLY);
  if (fd < 0)
    throw std::runtime_error(state_file.string() + ": cannot open the fake DAQ's state file: " + std::strerror(errno));
  void* p = ::mmap(nullptr, sizeof(FakeDaqState), PROT_READ, MAP_SHARED, fd, 0);
  ::close(fd);
  if (p == MAP_FAILED)
    throw std::runtime_error(state_file.string() + ": cannot map the fake DAQ's state: " + std::strerror(errno));
  const auto* state = static_cast<const FakeDaqState*>(p);
  if (state->magic != kFakeDaqMagic) {
    ::munmap(p, sizeof(FakeDaqState));
    throw std::runtime_error(state_file.string() + ": not a fake DAQ state file");
  }
  return std::shared_ptr<const FakeDaqState>(
      state, [](const FakeDaqState* s) { ::munmap(const_cast<FakeDaqState*>(s), sizeof(FakeDaqState)); });
}

bool amplifierEnabled(const FakeDaqState& state, std::int64_t now_ns, double timeout_s) noexcept {
  return state.enable_changes > 0 && static_cast<double>(now_ns - state.enable_changed_ns) * 1e-9 <= timeout_s;
}

bool amplifierEnabledPeriods(const FakeDaqState& state, std::uint64_t timeout_periods) noexcept {
  return state.enable_changes > 0 && state.periods - state.enable_changed_period <= timeout_periods;
}

// --- the comedilib stand-in ------------------------------------------------------------------

namespace fakedaq_api {

struct comedi_t {
  FakeDaqState* state = nullptr;
  comedi_range ai{};
  comedi_range ao{};
  comedi_range dio{0.0, 1.0, 0};
};

namespace {

constexpr unsigned kAi = 0;
constexpr unsigned kAo = 1;
constexpr unsigned kDio = 2;
thread_local int g_errno = 0;
std::atomic<comedi_oor_behavior> g_oor{COMEDI_OOR_NUMBER};

int fail(int error) noexcept {
  g_errno = error;
  return -1;
}

int channels(const comedi_t* d, unsigned sub) noexcept {
  switch (sub) {
    case kAi:
      return d->state->ai_channels;
    case kAo:
      return d->state->ao_channels;
    case kDio:
      return d->state->dio_channels;
    default:
      return -1;
  }
}

}  // namespace

comedi_t* comedi_open(const char* filename) {
  std::lock_guard lock(registryMutex());
  const auto it = registry().find(filename != nullptr ? filename : "");
  if (it == registry().end()) {
    g_errno = ENOENT;
    return nullptr;
  }
  auto* d = new comedi_t;
  d->state = it->second;
  d->ai = {it->second->ai.min_v, it->second->ai.max_v, 0};
  d->ao = {it->second->ao.min_v, it->second->ao.max_v, 0};
  return d;
}

int comedi_close(comedi_t* device) {
  delete device;
  return 0;
}

int comedi_errno() {
  return g_errno;
}

const char* comedi_strerror(int error) {
  return std::strerror(error);
}

int comedi_find_subdevice_by_type(comedi_t* device, int type, unsigned int start_subdevice) {
  if (device == nullptr) return fail(EINVAL);
  const unsigned sub = type == kSubdeviceAnalogInput    ? kAi
                       : type == kSubdeviceAnalogOutput ? kAo
                       : type == kSubdeviceDigitalIo    ? kDio
                                                        : 99;
  if (sub == 99 || sub < start_subdevice) return fail(ENODEV);
  return static_cast<int>(sub);
}

int comedi_get_n_channels(comedi_t* device, unsigned int subdevice) {
  if (device == nullptr) return fail(EINVAL);
  const int n = channels(device, subdevice);
  return n < 0 ? fail(EINVAL) : n;
}

lsampl_t comedi_get_maxdata(comedi_t* device, unsigned int subdevice, unsigned int channel) {
  if (device == nullptr || static_cast<int>(channel) >= channels(device, subdevice)) {
    g_errno = EINVAL;
    return 0;
  }
  return subdevice == kAi ? device->state->ai.maxdata : subdevice == kAo ? device->state->ao.maxdata : 1;
}

comedi_range* comedi_get_range(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int range) {
  if (device == nullptr || range != 0 || static_cast<int>(channel) >= channels(device, subdevice)) {
    g_errno = EINVAL;
    return nullptr;
  }
  return subdevice == kAi ? &device->ai : subdevice == kAo ? &device->ao : &device->dio;
}

int comedi_data_read(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int range,
                     unsigned int /*aref*/, lsampl_t* data) {
  if (device == nullptr || range != 0 || static_cast<int>(channel) >= channels(device, subdevice) || data == nullptr) {
    return fail(EINVAL);
  }
  if (subdevice == kAi) {
    *data = device->state->ai_codes[channel];
  } else if (subdevice == kAo) {
    *data = device->state->ao_codes[channel];  // read-back, as comedi_test's loop-back
  } else {
    *data = (device->state->dio_levels >> channel) & 1u;
  }
  return 1;
}

int comedi_data_write(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int range,
                      unsigned int /*aref*/, lsampl_t data) {
  if (device == nullptr || subdevice != kAo || range != 0 || static_cast<int>(channel) >= device->state->ao_channels) {
    return fail(EINVAL);
  }
  device->state->ao_codes[channel] = std::min<lsampl_t>(data, device->state->ao.maxdata);
  device->state->writer_pid = static_cast<std::int32_t>(::getpid());
  return 1;
}

int comedi_dio_config(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int direction) {
  if (device == nullptr || subdevice != kDio || static_cast<int>(channel) >= device->state->dio_channels)
    return fail(EINVAL);
  if (direction == kDigitalOutput) {
    device->state->dio_outputs |= 1u << channel;
  } else {
    device->state->dio_outputs &= ~(1u << channel);
  }
  return 1;
}

int comedi_dio_write(comedi_t* device, unsigned int subdevice, unsigned int channel, unsigned int bit) {
  if (device == nullptr || subdevice != kDio || static_cast<int>(channel) >= device->state->dio_channels)
    return fail(EINVAL);
  FakeDaqState& s = *device->state;
  if (((s.dio_outputs >> channel) & 1u) == 0) return fail(EINVAL);  // not configured as an output
  const std::uint32_t before = s.dio_levels;
  s.dio_levels = bit != 0 ? (before | (1u << channel)) : (before & ~(1u << channel));
  if (static_cast<int>(channel) == s.enable_line && s.dio_levels != before) {
    s.enable_changed_ns = monotonicNs();
    s.enable_changed_period = s.periods;
    ++s.enable_changes;
  }
  return 1;
}

double comedi_to_phys(lsampl_t data, const comedi_range* range, lsampl_t maxdata) {
  if (range == nullptr) return std::numeric_limits<double>::quiet_NaN();
  return codeToVolts(data, {range->min, range->max, maxdata}, g_oor.load(std::memory_order_relaxed) == COMEDI_OOR_NAN);
}

lsampl_t comedi_from_phys(double data, const comedi_range* range, lsampl_t maxdata) {
  if (range == nullptr) return 0;
  return voltsToCode(data, {range->min, range->max, maxdata});
}

comedi_oor_behavior comedi_set_global_oor_behavior(comedi_oor_behavior behavior) {
  return g_oor.exchange(behavior);
}

comedi_calibration_t* comedi_parse_calibration_file(const char* /*file*/) {
  g_errno = ENOENT;  // the fake board is not soft-calibrated
  return nullptr;
}

void comedi_cleanup_calibration(comedi_calibration_t* /*calibration*/) {}

int comedi_get_softcal_converter(unsigned, unsigned, unsigned, comedi_conversion_direction, const comedi_calibration_t*,
                                 comedi_polynomial_t*) {
  return fail(EINVAL);
}

double comedi_to_physical(lsampl_t data, const comedi_polynomial_t* polynomial) {
  // comedilib's evaluation: sum of c_i (data - origin)^i.
  double value = 0.0;
  double term = 1.0;
  const double x = static_cast<double>(data) - polynomial->expansion_origin;
  for (unsigned i = 0; i <= polynomial->order && i < static_cast<unsigned>(kMaxPolynomialCoefficients); ++i) {
    value += polynomial->coefficients[i] * term;
    term *= x;
  }
  return value;
}

}  // namespace fakedaq_api

// --- the rig ---------------------------------------------------------------------------------

FakeDaqRig::FakeDaqRig(FakeDaqBoard& board, SimulatedArm& arm, const DaqConfig& map, double watchdog_timeout_s)
    : board_(board),
      arm_(arm),
      map_(map),
      timeout_periods_(static_cast<std::uint64_t>(std::llround(watchdog_timeout_s / arm.period()))),
      volts_(IoVector::Zero(arm.numJoints())) {
  checkChannelMapFitsArm(map, arm, "fake DAQ");
  publishReadings();
}

void FakeDaqRig::publishReadings() noexcept {
  FakeDaqState& s = board_.state();
  for (int k = 0; k < arm_.numJoints(); ++k) {
    const DaqJoint& j = map_.joints[static_cast<std::size_t>(k)];
    s.ai_codes[j.potentiometer.channel] = static_cast<std::uint32_t>(arm_.reading(k).q_counts);
    s.ai_codes[j.load_cell.channel] = static_cast<std::uint32_t>(arm_.reading(k).tau_counts);
    // The transducers' outputs (checkChannelMapFitsArm: wired only where the plant has them).
    if (j.hasPressures()) {
      s.ai_codes[j.pressure_a.channel] = physicalToInputCode(j.pressure_a.calibration, arm_.reading(k).p_a_pa, s.ai);
      s.ai_codes[j.pressure_b.channel] = physicalToInputCode(j.pressure_b.calibration, arm_.reading(k).p_b_pa, s.ai);
    }
  }
}

core::RtStatus FakeDaqRig::advance() noexcept {
  FakeDaqState& s = board_.state();
  // The amplifiers follow the analog outputs while the hardware watchdog keeps them enabled.
  const bool enabled = amplifierEnabledPeriods(s, timeout_periods_);
  for (int k = 0; k < arm_.numJoints(); ++k) {
    const unsigned ch = static_cast<unsigned>(map_.joints[static_cast<std::size_t>(k)].valve.channel);
    volts_[k] = enabled ? codeToVolts(s.ao_codes[ch], s.ao, false) : 0.0;
  }
  const core::RtStatus status = arm_.advance(volts_);
  ++s.periods;
  publishReadings();
  return status;
}

std::unique_ptr<IoDevice> makeFakeDaqIoDevice(const DaqConfig& map, const arm::ArmModel& model, double period_s,
                                              const IoSafetyParams& safety, FakeDaqRig* rig) {
  BoardClock clock;
  if (rig != nullptr) {
    clock.context = rig;
    clock.before_read = [](void* context) noexcept { return static_cast<FakeDaqRig*>(context)->advance(); };
  }
  return std::make_unique<fakedaq_board::ComediBackend>(map, fakedaq_board::mapJoints(map, model), period_s, safety,
                                                        "fakedaq", clock);
}

}  // namespace fullarm::hil
