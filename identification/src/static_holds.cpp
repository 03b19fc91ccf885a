#include "fullarm/identification/static_holds.hpp"

#include <cmath>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>

#include "device_run.hpp"
#include "fullarm/identification/signal_csv.hpp"

namespace fullarm::identification {
namespace {

std::string qColumn(const std::string& joint) {
  return "q_" + joint + "_rad";
}
std::string tauColumn(const std::string& joint) {
  return "tau_" + joint + "_nm";
}

std::vector<std::string> holdColumns(const std::vector<std::string>& joint_names) {
  std::vector<std::string> names{"time_s", "posture_index", "side_sign"};
  for (const auto& j : joint_names) names.push_back(qColumn(j));
  for (const auto& j : joint_names) names.push_back(tauColumn(j));
  return names;
}

}  // namespace

StaticHoldRun runStaticHolds(hil::IoDevice& device, const std::vector<Eigen::VectorXd>& postures_rad,
                             const StaticHoldOptions& options) {
  if (device.state() == hil::IoState::kUnconfigured) device.configure();
  const int n = device.numJoints();
  if (static_cast<int>(options.min_rad.size()) != n || static_cast<int>(options.max_rad.size()) != n) {
    throw std::invalid_argument("static holds: limits for " + std::to_string(options.min_rad.size()) + "/" +
                                std::to_string(options.max_rad.size()) + " joints, the device has " +
                                std::to_string(n));
  }
  if (!(options.move_s > 0.0 && options.approach_s > 0.0 && options.settle_s >= 0.0 && options.average_s > 0.0 &&
        options.move_speed_radps > 0.0 && options.approach_rad >= 0.0 && options.hold_gain_v_per_rad > 0.0)) {
    throw std::invalid_argument("static holds: times and the hold gain must be positive, the approach non-negative");
  }
  for (std::size_t p = 0; p < postures_rad.size(); ++p) {
    const auto& q = postures_rad[p];
    if (q.size() != n) {
      throw std::invalid_argument("static holds: posture " + std::to_string(p) + " has " + std::to_string(q.size()) +
                                  " angles, the device has " + std::to_string(n) + " joints");
    }
    for (int k = 0; k < n; ++k) {
      const auto ks = static_cast<std::size_t>(k);
      const double lo = options.min_rad[ks] + options.limit_margin_rad;
      const double hi = options.max_rad[ks] - options.limit_margin_rad;
      if (!(q[k] - options.approach_rad >= lo && q[k] + options.approach_rad <= hi)) {
        throw std::invalid_argument("static holds: posture " + std::to_string(p) + ", joint " + std::to_string(k) +
                                    ": " + std::to_string(q[k]) + " rad +- the approach " +
                                    std::to_string(options.approach_rad) + " rad is not inside " + std::to_string(lo) +
                                    ".." + std::to_string(hi) + " rad (limits less the margin)");
      }
    }
  }

  StaticHoldRun run;
  hil::JointSample sample;
  detail::PacedReader reader(device, options.before_read);
  const auto read = [&] { return reader.read(sample); };
  const auto readFailure = [&] { return reader.failure(); };
  if (!read()) {
    throw hil::DeviceError("static holds: the device could not be read before anything moved: " + readFailure());
  }
  device.activate();
  detail::DeactivateOnExit guard{device};

  const double dt = device.period();
  auto steps = [dt](double s) { return static_cast<long>(std::llround(s / dt)); };
  const long min_move_steps = std::max(1L, steps(options.move_s));
  const long approach_steps = std::max(1L, steps(options.approach_s));
  const long settle_steps = steps(options.settle_s);
  const long average_steps = std::max(1L, steps(options.average_s));
  hil::IoVector command = hil::IoVector::Zero(n);
  Eigen::VectorXd target = Eigen::VectorXd::Map(sample.q_rad.data(), n);
  bool first_read = true;
  // Each joint's band: its first move's from where it starts (detail::firstMoveBand), then, once
  // that move has ended, its limits less the margin.
  std::vector<detail::LimitBand> bands(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const auto ks = static_cast<std::size_t>(k);
    bands[ks] = detail::firstMoveBand(target[k], options.min_rad[ks], options.max_rad[ks], options.limit_margin_rad);
  }
  const auto endFirstMove = [&] {
    for (std::size_t k = 0; k < bands.size(); ++k) {
      bands[k] = {options.min_rad[k] + options.limit_margin_rad, options.max_rad[k] - options.limit_margin_rad};
    }
  };

  // One control period towards `target`: read (the first one is the read above), check, write.
  auto step = [&](std::string& failure) -> bool {
    if (!first_read && !read()) {
      failure = readFailure();
      return false;
    }
    first_read = false;
    for (int k = 0; k < n; ++k) {
      const auto ks = static_cast<std::size_t>(k);
      const double q = sample.q_rad[k];
      if (!std::isfinite(q) || !std::isfinite(sample.tau_load_cell_nm[k])) {
        failure = "joint " + std::to_string(k) + ": reading not finite (out of range)";
        return false;
      }
      if (!bands[ks].contains(q)) {
        failure = "joint " + std::to_string(k) + " at " + std::to_string(q) + " rad, within " +
                  std::to_string(options.limit_margin_rad) + " rad of its limits " +
                  std::to_string(options.min_rad[ks]) + ".." + std::to_string(options.max_rad[ks]) + " rad";
        return false;
      }
      if (std::abs(target[k] - q) > options.max_error_rad) {
        failure = "joint " + std::to_string(k) + " is " + std::to_string(std::abs(target[k] - q)) +
                  " rad from its hold target (more than " + std::to_string(options.max_error_rad) + " rad)";
        return false;
      }
      command[k] = options.hold_gain_v_per_rad * (target[k] - q);
    }
    if (!device.write(command).ok()) {
      failure = std::string("device write failed: ") + device.status().message;
      return false;
    }
    return true;
  };

  for (std::size_t p = 0; p < postures_rad.size(); ++p) {
    const Eigen::VectorXd& posture = postures_rad[p];
    for (const int side : {+1, -1}) {
      const Eigen::VectorXd from = target;
      const Eigen::VectorXd start = posture + Eigen::VectorXd::Constant(n, side * options.approach_rad);
      // The move takes move_s, longer when a joint would go faster than move_speed_radps.
      const double distance = (start - from).cwiseAbs().maxCoeff();
      const long move_steps = std::max(min_move_steps, steps(distance / options.move_speed_radps));
      std::string failure;
      bool ok = true;
      for (long s = 1; ok && s <= move_steps; ++s) {
        target = from + detail::blend(static_cast<double>(s) / static_cast<double>(move_steps)) * (start - from);
        ok = step(failure);
      }
      endFirstMove();
      for (long s = 1; ok && s <= approach_steps; ++s) {
        target =
            start + detail::blend(static_cast<double>(s) / static_cast<double>(approach_steps)) * (posture - start);
        ok = step(failure);
      }
      target = posture;
      for (long s = 0; ok && s < settle_steps; ++s) ok = step(failure);
      StaticHold hold;
      hold.posture_index = static_cast<int>(p);
      hold.side = side;
      hold.q_rad = Eigen::VectorXd::Zero(n);
      hold.tau_nm = Eigen::VectorXd::Zero(n);
      for (long s = 0; ok && s < average_steps; ++s) {
        ok = step(failure);
        if (!ok) break;
        hold.q_rad += Eigen::VectorXd::Map(sample.q_rad.data(), n);
        hold.tau_nm += Eigen::VectorXd::Map(sample.tau_load_cell_nm.data(), n);
        hold.time_s = sample.t_s;
      }
      if (!ok) {
        run.stop_reason = "posture " + std::to_string(p) + (side > 0 ? " from above: " : " from below: ") + failure;
        return run;
      }
      hold.q_rad /= static_cast<double>(average_steps);
      hold.tau_nm /= static_cast<double>(average_steps);
      run.holds.push_back(std::move(hold));
      if (options.on_hold) options.on_hold(run.holds.back());
    }
  }
  run.completed = true;
  return run;
}

std::vector<CombinedHold> combineSides(const std::vector<StaticHold>& holds) {
  std::map<int, std::pair<const StaticHold*, const StaticHold*>> by_posture;  // (above, below)
  for (const auto& h : holds) {
    auto& slot = by_posture[h.posture_index];
    const StaticHold*& side = h.side > 0 ? slot.first : slot.second;
    if (side != nullptr) {
      throw std::invalid_argument("static holds: posture " + std::to_string(h.posture_index) + " is held twice from " +
                                  (h.side > 0 ? "above" : "below"));
    }
    side = &h;
  }
  std::vector<CombinedHold> out;
  for (const auto& [index, pair] : by_posture) {
    if (pair.first == nullptr || pair.second == nullptr) {
      throw std::invalid_argument("static holds: posture " + std::to_string(index) + " is held only from " +
                                  (pair.first != nullptr ? "above" : "below") +
                                  " (both sides are needed to cancel the friction at rest)");
    }
    if (pair.first->q_rad.size() != pair.second->q_rad.size() ||
        pair.first->tau_nm.size() != pair.second->tau_nm.size()) {
      throw std::invalid_argument("static holds: posture " + std::to_string(index) + ": sides of different sizes");
    }
    out.push_back(
        {index, 0.5 * (pair.first->q_rad + pair.second->q_rad), 0.5 * (pair.first->tau_nm + pair.second->tau_nm)});
  }
  return out;
}

Eigen::VectorXd holdConfiguration(const Eigen::VectorXd& base_configuration, const arm::JointSelection& device_joints,
                                  const Eigen::VectorXd& q_device_rad) {
  if (base_configuration.size() != device_joints.numModelJoints() || q_device_rad.size() != device_joints.size()) {
    throw std::invalid_argument("static holds: a configuration of " + std::to_string(base_configuration.size()) +
                                " and a hold of " + std::to_string(q_device_rad.size()) +
                                " angles for a selection of " + std::to_string(device_joints.size()) + " of " +
                                std::to_string(device_joints.numModelJoints()) + " joints");
  }
  Eigen::VectorXd q = base_configuration;
  device_joints.scatter(q_device_rad, q);
  return q;
}

void writeStaticHoldsCsv(const std::filesystem::path& file, const std::vector<StaticHold>& holds,
                         const std::vector<std::string>& joint_names) {
  const auto n = static_cast<Eigen::Index>(joint_names.size());
  SignalTable table;
  table.names = holdColumns(joint_names);
  table.columns.assign(table.names.size(), {});
  for (const auto& h : holds) {
    if (h.q_rad.size() != n || h.tau_nm.size() != n) {
      throw std::invalid_argument("static holds: a hold of " + std::to_string(h.q_rad.size()) + " angles for " +
                                  std::to_string(n) + " joint names");
    }
    table.columns[0].push_back(h.time_s);
    table.columns[1].push_back(h.posture_index);
    table.columns[2].push_back(h.side);
    for (Eigen::Index k = 0; k < n; ++k) {
      table.columns[static_cast<std::size_t>(3 + k)].push_back(h.q_rad[k]);
      table.columns[static_cast<std::size_t>(3 + n + k)].push_back(h.tau_nm[k]);
    }
  }
  writeSignalCsv(file, table);
}

std::vector<StaticHold> parseStaticHoldsCsv(std::string_view text, const std::string& source,
                                            const std::vector<std::string>& joint_names) {
  const SignalTable table = parseSignalCsv(text, source, holdColumns(joint_names));
  const auto n = static_cast<Eigen::Index>(joint_names.size());
  const auto& time = table.column("time_s");
  const auto& index = table.column("posture_index");
  const auto& side = table.column("side_sign");
  std::vector<const std::vector<double>*> q_cols;
  std::vector<const std::vector<double>*> tau_cols;
  for (const auto& j : joint_names) {
    q_cols.push_back(&table.column(qColumn(j)));
    tau_cols.push_back(&table.column(tauColumn(j)));
  }
  std::vector<StaticHold> holds;
  for (std::size_t r = 0; r < table.rows(); ++r) {
    const std::size_t line = r + 2;  // the header is line 1
    if (!(index[r] >= 0.0 && index[r] == std::floor(index[r]) && index[r] < 1e9)) {
      std::ostringstream v;
      v << index[r];
      throw CsvFormatError(source, line, "posture_index " + v.str() + " is not a non-negative integer");
    }
    if (side[r] != 1.0 && side[r] != -1.0) {
      std::ostringstream v;
      v << side[r];
      throw CsvFormatError(source, line, "side_sign " + v.str() + " is neither +1 (from above) nor -1 (from below)");
    }
    StaticHold h;
    h.time_s = time[r];
    h.posture_index = static_cast<int>(index[r]);
    h.side = side[r] > 0.0 ? 1 : -1;
    h.q_rad.resize(n);
    h.tau_nm.resize(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      h.q_rad[k] = (*q_cols[static_cast<std::size_t>(k)])[r];
      h.tau_nm[k] = (*tau_cols[static_cast<std::size_t>(k)])[r];
    }
    holds.push_back(std::move(h));
  }
  return holds;
}

std::vector<StaticHold> readStaticHoldsCsv(const std::filesystem::path& file,
                                           const std::vector<std::string>& joint_names) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw CsvFormatError(file.string(), 0, "cannot be opened");
  std::ostringstream text;
  text << in.rdbuf();
  return parseStaticHoldsCsv(text.str(), file.string(), joint_names);
}

}  // namespace fullarm::identification
