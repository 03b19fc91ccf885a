#include "fullarm/identification/experiment.hpp"

#include <cmath>
#include <stdexcept>

#include "device_run.hpp"

namespace fullarm::identification {

ExperimentResult runExperiment(hil::IoDevice& device, const SampledSignal& excitation,
                               const ExperimentOptions& options) {
  if (device.state() == hil::IoState::kUnconfigured) device.configure();
  const int n = device.numJoints();
  const int j = options.joint;
  if (j < 0 || j >= n) {
    throw std::invalid_argument("experiment: joint " + std::to_string(j) + " outside the device's " +
                                std::to_string(n) + " joints");
  }
  if (std::abs(excitation.sample_period_s - device.period()) > 1e-12 * device.period()) {
    throw std::invalid_argument("experiment: excitation sampled every " + std::to_string(excitation.sample_period_s) +
                                " s, the device runs every " + std::to_string(device.period()) + " s");
  }
  const double lo = options.min_rad + options.limit_margin_rad;
  const double hi = options.max_rad - options.limit_margin_rad;
  if (!(lo < hi)) {
    throw std::invalid_argument("experiment: limits " + std::to_string(options.min_rad) + ".." +
                                std::to_string(options.max_rad) + " rad leave no room inside a margin of " +
                                std::to_string(options.limit_margin_rad) + " rad");
  }

  ExperimentResult result;
  result.log.names = kExperimentColumns;
  result.log.columns.assign(kExperimentColumns.size(), {});
  for (auto& c : result.log.columns) c.reserve(excitation.value_v.size());

  hil::JointSample sample;
  detail::PacedReader reader(device, options.before_read);
  const auto read = [&] { return reader.read(sample); };
  const auto readFailure = [&] { return reader.failure(); };
  if (!read()) throw std::runtime_error("experiment: the device could not be read: " + readFailure());
  result.hold_rad.assign(sample.q_rad.data(), sample.q_rad.data() + n);
  if (!(sample.q_rad[j] >= lo && sample.q_rad[j] <= hi)) {
    throw std::invalid_argument("experiment: joint " + std::to_string(j) + " starts at " +
                                std::to_string(sample.q_rad[j]) + " rad, outside " + std::to_string(lo) + ".." +
                                std::to_string(hi) + " rad (limits less the margin)");
  }

  device.activate();
  detail::DeactivateOnExit guard{device};
  const auto settle_steps = static_cast<std::size_t>(std::llround(options.settle_s / device.period()));
  const std::size_t total = settle_steps + excitation.value_v.size();
  hil::IoVector command = hil::IoVector::Zero(n);
  for (std::size_t step = 0; step < total; ++step) {
    if (step > 0 && !read()) {
      result.stop_reason = readFailure();
      return result;
    }
    const double q = sample.q_rad[j];
    if (!std::isfinite(q) || q < lo || q > hi) {
      result.stop_reason = "joint " + std::to_string(j) + " at " + std::to_string(q) + " rad, within " +
                           std::to_string(options.limit_margin_rad) + " rad of its limits " +
                           std::to_string(options.min_rad) + ".." + std::to_string(options.max_rad) + " rad";
      return result;
    }
    if (!std::isfinite(sample.tau_load_cell_nm[j])) {
      result.stop_reason = "joint " + std::to_string(j) + ": load-cell reading out of range";
      return result;
    }
    for (int k = 0; k < n; ++k) {
      if (k == j) continue;
      if (!std::isfinite(sample.q_rad[k]) ||
          std::abs(sample.q_rad[k] - result.hold_rad[static_cast<std::size_t>(k)]) > options.held_drift_limit_rad) {
        result.stop_reason = "held joint " + std::to_string(k) + " left its hold by more than " +
                             std::to_string(options.held_drift_limit_rad) + " rad";
        return result;
      }
      command[k] = options.held_gain_v_per_rad * (result.hold_rad[static_cast<std::size_t>(k)] - sample.q_rad[k]);
    }
    const bool exciting = step >= settle_steps;
    const double r = exciting ? excitation.value_v[step - settle_steps] : 0.0;
    command[j] = options.hold_gain_v_per_rad * (result.hold_rad[static_cast<std::size_t>(j)] - q) + r;
    if (!device.write(command).ok()) {
      result.stop_reason = std::string("device write failed: ") + device.status().message;
      return result;
    }
    if (exciting) {
      auto& c = result.log.columns;
      const double t0 = c[0].empty() ? sample.t_s : c[0].front();
      c[0].push_back(options.log_control_time ? t0 + static_cast<double>(step - settle_steps) * device.period()
                                              : sample.t_s);
      c[1].push_back(r);
      c[2].push_back(device.appliedCommand()[j]);
      c[3].push_back(q);
      c[4].push_back(sample.tau_load_cell_nm[j]);
    }
  }
  result.completed = true;
  return result;
}

}  // namespace fullarm::identification
