#include "command_device.hpp"

#include <time.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_values.hpp"
#include "fullarm/core/config_error.hpp"
#include "fullarm/hil/run_recording.hpp"

namespace fullarm::app {

hil::IoKind commandIoKind(const std::string& name) {
  if (name == "sim") return hil::IoKind::kSim;
  if (name == "fakedaq") return hil::IoKind::kFakeDaq;
  if (name == "comedi") return hil::IoKind::kComedi;
  if (name == "lcm") return hil::IoKind::kLcm;
  throw core::ConfigError({}, "--io", "'" + name + "': expected sim, fakedaq, comedi or lcm");
}

PeriodClock::PeriodClock(double period_s) {
  if (!(std::isfinite(period_s) && period_s > 0.0)) {
    throw std::invalid_argument("period clock: the period must be finite and positive, got " +
                                std::to_string(period_s) + " s");
  }
  period_ns_ = static_cast<long>(std::llround(period_s * 1e9));
}

bool PeriodClock::operator()() {
  constexpr long kSecond = 1'000'000'000L;
  if (!started_) {
    clock_gettime(CLOCK_MONOTONIC, &next_);
    started_ = true;
    return true;
  }
  next_.tv_nsec += period_ns_;
  while (next_.tv_nsec >= kSecond) {
    next_.tv_nsec -= kSecond;
    ++next_.tv_sec;
  }
  int error = 0;
  while ((error = clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &next_, nullptr)) == EINTR) {
  }
  timespec now{};
  clock_gettime(CLOCK_MONOTONIC, &now);
  const long long late_ns =
      (static_cast<long long>(now.tv_sec) - next_.tv_sec) * kSecond + (now.tv_nsec - next_.tv_nsec);
  if (error != 0 || late_ns > period_ns_ / 2) {
    ++overruns_;
    next_ = now;  // the deadlines restart from now: no burst of back-to-back periods
    return false;
  }
  return true;
}

std::unique_ptr<CommandDevice> openCommandDevice(hil::IoKind kind, const arm::ArmModel& model,
                                                 const plant::PlantConfig& plant, const Eigen::VectorXd& posture,
                                                 std::uint64_t seed, const std::string& daq_config,
                                                 const std::string& hil_config, double period_s,
                                                 const std::string& only_joint, const std::string& lcm_url) {
  auto d = std::make_unique<CommandDevice>();
  d->loop = hil::loadHilConfig(configPathOr(hil_config, hil::defaultHilConfigPath));
  if (std::abs(d->loop.control_period_s - period_s) > 1e-12) {
    throw core::ConfigError(d->loop.source, "control_period_s",
                            "is " + std::to_string(d->loop.control_period_s) + " s: expected " +
                                std::to_string(period_s) + " s, the period the experiments are designed for");
  }
  d->plant = plant;
  d->plant.solver.integrator = d->loop.sim_integrator;
  d->plant.seed = seed;
  if (kind == hil::IoKind::kFakeDaq || kind == hil::IoKind::kComedi) {
    d->daq = hil::loadDaqConfig(configPathOr(daq_config, hil::defaultDaqConfigPath), model);
  }
  if (!only_joint.empty() && kind != hil::IoKind::kComedi && kind != hil::IoKind::kLcm) {
    const auto k = static_cast<std::size_t>(plant::findPlantJoint(d->plant, only_joint));
    d->plant.joints = {d->plant.joints[k]};
    if (kind == hil::IoKind::kFakeDaq) {
      const auto j = std::find_if(d->daq.joints.begin(), d->daq.joints.end(),
                                  [&](const hil::DaqJoint& dj) { return dj.name == d->plant.joints[0].name; });
      if (j == d->daq.joints.end()) {
        throw core::ConfigError(d->daq.source, "joints", "has no channels for " + d->plant.joints[0].name);
      }
      d->daq.joints = {*j};
    }
  }
  hil::IoBackendOptions io;
  io.io = kind;
  io.period_s = d->loop.control_period_s;
  io.latency_samples = d->loop.latency_samples;
  io.safety = d->loop.io_safety;
  io.plant = &d->plant;
  io.posture = posture;
  io.daq = &d->daq;
  if (kind == hil::IoKind::kLcm) {
    // The node serves its plant file's joints; a reading may take as long as a loaded machine
    // needs (lockstep: the node advances one period per command).
    std::vector<int> indices;
    for (const plant::JointParams& j : d->plant.joints) indices.push_back(model.jointIndex(j.name));
    io.lcm_joints = arm::JointSelection(model.numJoints(), indices);
    io.lcm_url = lcm_url;
    // A missed reply would repeat the last reading in the log: it stops the experiment instead.
    io.lcm_max_missed_replies = 1;
  }
  d->backend = std::make_unique<hil::IoBackend>(model, io);
  d->backend->device().configure();  // opens the board: a missing one is reported before anything runs
  if (const auto* lcm = dynamic_cast<const hil::LcmIoDevice*>(&d->backend->device()); lcm != nullptr) {
    d->node = *lcm->nodeInfo();  // configure() succeeded: the node described itself
    d->lcm_url = lcm_url.empty() ? std::string(hil::kDefaultLcmUrl) : lcm_url;
    const std::string& url = d->lcm_url;
    if (d->node->scripted_user) {
      throw hil::DeviceError("lcm I/O: the node at " + url +
                             " has a scripted user strapped in, who moves the arm; the experiments assume nobody "
                             "does: start it with `fullarm plant serve --no-user`");
    }
    // A simulated node names its plant file and the file's SHA-256: the limits and the fit's start
    // come from --plant, so it must be the same file's contents (its name may differ).
    const std::string& served = d->node->plant;
    const std::size_t hash_at = served.rfind(" sha256 ");
    if (hash_at != std::string::npos && !plant.source.empty()) {
      const std::string node_hash = served.substr(hash_at + 8);
      const std::string own_hash = hil::sha256File(plant.source);
      if (node_hash != own_hash) {
        throw core::ConfigError({}, "--plant",
                                plant.source.string() + " (sha256 " + own_hash +
                                    ") is not the plant file the node at " + url + " serves (" + served +
                                    "): give --plant the node's --plant-config");
      }
    }
  }
  // The real board, or a node serving real hardware, answers a read at once: the reads are paced.
  if (kind == hil::IoKind::kComedi || (d->node && !d->node->simulated)) d->pace = PeriodClock(d->loop.control_period_s);
  return d;
}

void checkNodeArmMotion(const CommandDevice& device, bool moves, bool confirmed, const std::string& required_with,
                        const std::string& why) {
  if (!device.node) return;
  if (moves && !device.node->simulated && !confirmed) {
    throw core::ConfigError(
        {}, "--confirm-arm-motion",
        "is required with " + required_with + " (the node at " + device.lcm_url + " says it is not simulated): " + why);
  }
  if (confirmed && device.node->simulated) {
    throw core::ConfigError({}, "--confirm-arm-motion",
                            "the node at " + device.lcm_url + " serves a simulated arm: no real arm moves");
  }
}

}  // namespace fullarm::app
