#include "fullarm/identification/experiment.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string_view>
#include <utility>

#include "device_run.hpp"

namespace fullarm::identification {

std::string heldAngleColumn(const std::string& joint) {
  return "held_" + joint + "_rad";
}

bool isLoggableJointName(const std::string& name) noexcept {
  return !name.empty() && name.find_first_of(", \t\r\n\"") == std::string::npos;
}

std::vector<HeldAngle> heldAngles(const SignalTable& log) {
  std::vector<HeldAngle> held;
  constexpr std::string_view kPrefix = "held_";
  constexpr std::string_view kSuffix = "_rad";
  for (std::size_t c = 0; c < log.names.size() && c < log.columns.size(); ++c) {
    const std::string& name = log.names[c];
    if (name.size() <= kPrefix.size() + kSuffix.size() || !name.starts_with(kPrefix) || !name.ends_with(kSuffix)) {
      continue;
    }
    const std::vector<double>& column = log.columns[c];
    double sum = 0.0;
    for (double v : column) sum += v;
    held.push_back(
        {name.substr(kPrefix.size(), name.size() - kPrefix.size() - kSuffix.size()),
         column.empty() ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(column.size())});
  }
  return held;
}

ExperimentResult runExperiment(hil::IoDevice& device, const SampledSignal& excitation,
                               const ExperimentOptions& options) {
  return std::move(runExperiments(device, {excitation}, options).front());
}

std::vector<ExperimentResult> runExperiments(hil::IoDevice& device, const std::vector<SampledSignal>& excitations,
                                             const ExperimentOptions& options) {
  if (excitations.empty()) throw std::invalid_argument("experiment: no excitation");
  if (device.state() == hil::IoState::kUnconfigured) device.configure();
  const int n = device.numJoints();
  const int j = options.joint;
  if (j < 0 || j >= n) {
    throw std::invalid_argument("experiment: joint " + std::to_string(j) + " outside the device's " +
                                std::to_string(n) + " joints");
  }
  for (const SampledSignal& excitation : excitations) {
    if (std::abs(excitation.sample_period_s - device.period()) > 1e-12 * device.period()) {
      throw std::invalid_argument("experiment: excitation sampled every " + std::to_string(excitation.sample_period_s) +
                                  " s, the device runs every " + std::to_string(device.period()) + " s");
    }
  }
  const double lo = options.min_rad + options.limit_margin_rad;
  const double hi = options.max_rad - options.limit_margin_rad;
  if (!(lo < hi)) {
    throw std::invalid_argument("experiment: limits " + std::to_string(options.min_rad) + ".." +
                                std::to_string(options.max_rad) + " rad leave no room inside a margin of " +
                                std::to_string(options.limit_margin_rad) + " rad");
  }
  if (options.hold_rad && !(*options.hold_rad >= lo && *options.hold_rad <= hi)) {
    throw std::invalid_argument("experiment: hold angle " + std::to_string(*options.hold_rad) + " rad outside " +
                                std::to_string(lo) + ".." + std::to_string(hi) + " rad (limits less the margin)");
  }
  if (!(options.settle_s >= 0.0) || !std::isfinite(options.settle_s)) {
    throw std::invalid_argument("experiment: the settling time must be non-negative and finite");
  }
  if (!(options.move_s > 0.0 && options.move_speed_radps > 0.0 && options.move_max_error_rad > 0.0) ||
      !std::isfinite(options.move_s) || !std::isfinite(options.move_speed_radps) ||
      !std::isfinite(options.move_max_error_rad)) {
    throw std::invalid_argument("experiment: the move's time, speed and error limit must be positive and finite");
  }

  const bool log_held = !options.joint_names.empty();
  if (log_held) {
    if (options.joint_names.size() != static_cast<std::size_t>(n)) {
      throw std::invalid_argument("experiment: " + std::to_string(options.joint_names.size()) +
                                  " joint names for the device's " + std::to_string(n) + " joints");
    }
    for (std::size_t k = 0; k < options.joint_names.size(); ++k) {
      const std::string& name = options.joint_names[k];
      if (!isLoggableJointName(name)) {
        throw std::invalid_argument("experiment: joint name '" + name + "' cannot name a log column");
      }
      for (std::size_t other = 0; other < k; ++other) {
        if (options.joint_names[other] == name) {
          throw std::invalid_argument("experiment: joint name '" + name + "' given twice");
        }
      }
    }
  }

  std::vector<ExperimentResult> results(excitations.size());
  ExperimentResult& result = results.front();  // the first holds the log's layout and the holds
  hil::JointSample sample;
  detail::PacedReader reader(device, options.before_read);
  const auto read = [&] { return reader.read(sample); };
  const auto readFailure = [&] { return reader.failure(); };
  if (!read())
    throw hil::DeviceError("experiment: the device could not be read before anything moved: " + readFailure());
  // The driven joint's chamber pressures, where the device reads them, follow the five columns.
  const bool log_pressures = (sample.pressure_mask >> j & 1u) != 0;
  result.log.names = kExperimentColumns;
  if (log_pressures) result.log.names.insert(result.log.names.end(), kPressureColumns.begin(), kPressureColumns.end());
  const std::size_t first_held_column = result.log.names.size();
  if (log_held) {
    for (int k = 0; k < n; ++k) {
      if (k != j) result.log.names.push_back(heldAngleColumn(options.joint_names[static_cast<std::size_t>(k)]));
    }
  }
  result.log.columns.assign(result.log.names.size(), {});
  result.hold_rad.assign(sample.q_rad.data(), sample.q_rad.data() + n);
  const double start = sample.q_rad[j];
  const auto nameOf = [&](int k) {
    return log_held ? options.joint_names[static_cast<std::size_t>(k)] : "joint " + std::to_string(k);
  };
  const std::string joint_name = nameOf(j);
  const std::string limits = std::to_string(options.min_rad) + ".." + std::to_string(options.max_rad) + " rad";
  const std::string range = std::to_string(lo) + ".." + std::to_string(hi) + " rad (its limits " + limits +
                            " less the margin of " + std::to_string(options.limit_margin_rad) + " rad)";
  // A reading out of range, or beyond the joint's own limits, is no posture to move from: the
  // sensor, its calibration or the limits are wrong.
  if (!std::isfinite(start)) {
    throw hil::DeviceError("experiment: " + joint_name + " reads out of range before anything moved");
  }
  if (start < options.min_rad || start > options.max_rad) {
    throw hil::DeviceError("experiment: " + joint_name + " reads " + std::to_string(start) +
                           " rad, beyond its limits " + limits +
                           ": the reading or the limits are wrong (calibration, channel map, plant file)");
  }
  if (!options.hold_rad && !(start >= lo && start <= hi)) {
    throw ExperimentRefused(joint_name + " starts at " + std::to_string(start) + " rad: expected it inside " + range +
                            ", or a hold angle inside that range to move it to first");
  }
  const double hold = options.hold_rad.value_or(start);
  // The move to the hold angle (none without one) and the band the joint must stay in meanwhile.
  const double period = device.period();
  const std::size_t move_steps =
      options.hold_rad
          ? std::max<std::size_t>(
                1, static_cast<std::size_t>(std::llround(
                       std::max(options.move_s, std::abs(hold - start) / options.move_speed_radps) / period)))
          : 0;
  const detail::LimitBand held_band{lo, hi};
  const detail::LimitBand move_band =
      detail::firstMoveBand(start, options.min_rad, options.max_rad, options.limit_margin_rad);
  result.hold_rad[static_cast<std::size_t>(j)] = hold;
  for (std::size_t e = 0; e < excitations.size(); ++e) {
    if (e > 0) {
      results[e].log.names = result.log.names;
      results[e].log.columns.assign(result.log.names.size(), {});
      results[e].hold_rad = result.hold_rad;
    }
    for (auto& c : results[e].log.columns) c.reserve(excitations[e].value_v.size());
  }

  const auto settle_steps = static_cast<std::size_t>(std::llround(options.settle_s / period));
  // Each excitation after the move and its own settling time: [start, end) in steps.
  std::vector<std::size_t> excitation_start(excitations.size()), excitation_end(excitations.size());
  std::size_t total = move_steps;
  for (std::size_t e = 0; e < excitations.size(); ++e) {
    excitation_start[e] = total + settle_steps;
    excitation_end[e] = excitation_start[e] + excitations[e].value_v.size();
    total = excitation_end[e];
  }
  hil::IoVector command = hil::IoVector::Zero(n);
  std::size_t current = 0;  // the excitation being run or settled for
  // A stop ends the excitation under way; the ones after it do not run. (The results move out:
  // the guard deactivates the device once the return value is built.)
  const auto stop = [&](const std::string& reason) {
    results[current].stop_reason = reason;
    for (std::size_t e = current + 1; e < results.size(); ++e) results[e].stop_reason = "not run: " + reason;
    return std::move(results);
  };

  device.activate();
  detail::DeactivateOnExit guard{device};
  for (std::size_t step = 0; step < total; ++step) {
    while (step >= excitation_end[current]) {  // step < total: a later excitation remains
      results[current].completed = true;
      ++current;
    }
    if (step > 0 && !read()) return stop(readFailure());
    const double q = sample.q_rad[j];
    const bool moving = step < move_steps;
    const double target =
        moving ? start + detail::blend(static_cast<double>(step + 1) / static_cast<double>(move_steps)) * (hold - start)
               : hold;
    if (!std::isfinite(q) || !(moving ? move_band : held_band).contains(q)) {
      return stop(joint_name + " at " + std::to_string(q) + " rad, within " + std::to_string(options.limit_margin_rad) +
                  " rad of its limits " + std::to_string(options.min_rad) + ".." + std::to_string(options.max_rad) +
                  " rad" + (moving ? " (moving to its hold angle " + std::to_string(hold) + " rad)" : ""));
    }
    if (moving && std::abs(target - q) > options.move_max_error_rad) {
      return stop(joint_name + " is " + std::to_string(std::abs(target - q)) +
                  " rad from its target moving to its hold angle " + std::to_string(hold) + " rad (more than " +
                  std::to_string(options.move_max_error_rad) + " rad)");
    }
    if (!std::isfinite(sample.tau_load_cell_nm[j])) {
      return stop(joint_name + ": load-cell reading out of range");
    }
    if (log_pressures && ((sample.pressure_mask >> j & 1u) == 0 || !std::isfinite(sample.p_a_pa[j]) ||
                          !std::isfinite(sample.p_b_pa[j]))) {
      return stop(joint_name + ": chamber pressure reading missing or out of range");
    }
    for (int k = 0; k < n; ++k) {
      if (k == j) continue;
      if (!std::isfinite(sample.q_rad[k]) ||
          std::abs(sample.q_rad[k] - result.hold_rad[static_cast<std::size_t>(k)]) > options.held_drift_limit_rad) {
        return stop("held joint " + nameOf(k) + " left its hold by more than " +
                    std::to_string(options.held_drift_limit_rad) + " rad");
      }
      command[k] = options.held_gain_v_per_rad * (result.hold_rad[static_cast<std::size_t>(k)] - sample.q_rad[k]);
    }
    const bool exciting = step >= excitation_start[current];
    const double r = exciting ? excitations[current].value_v[step - excitation_start[current]] : 0.0;
    command[j] = options.hold_gain_v_per_rad * (target - q) + r;
    if (!device.write(command).ok()) {
      return stop(std::string("device write failed: ") + device.status().message);
    }
    if (exciting) {
      auto& c = results[current].log.columns;
      const double t0 = c[0].empty() ? sample.t_s : c[0].front();
      c[0].push_back(options.log_control_time ? t0 + static_cast<double>(step - excitation_start[current]) * period
                                              : sample.t_s);
      c[1].push_back(r);
      c[2].push_back(device.appliedCommand()[j]);
      c[3].push_back(q);
      c[4].push_back(sample.tau_load_cell_nm[j]);
      if (log_pressures) {
        c[5].push_back(sample.p_a_pa[j]);
        c[6].push_back(sample.p_b_pa[j]);
      }
      if (log_held) {
        std::size_t column = first_held_column;
        for (int k = 0; k < n; ++k) {
          if (k != j) c[column++].push_back(sample.q_rad[k]);
        }
      }
    }
  }
  // The one under way, and any after it with no steps of their own, ran whole.
  for (std::size_t e = current; e < results.size(); ++e) results[e].completed = true;
  return results;
}

}  // namespace fullarm::identification
