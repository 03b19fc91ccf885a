#include "fullarm/identification/experiment_lcm.hpp"

#include <array>
#include <cmath>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "fullarm/hil/run_log.hpp"
#include "fullarm/identification/experiment.hpp"
#include "fullarm_lcm/ident_experiment_t.hpp"
#include "fullarm_lcm/ident_experiment_v1_t.hpp"
#include "fullarm_lcm/ident_sample_t.hpp"
#include "fullarm_lcm/ident_sample_v1_t.hpp"

namespace fullarm::identification {
namespace {

constexpr int kMaxHeldJoints = 64;
// An ident_sample_t's row values, in the order of kExperimentColumns.
constexpr std::size_t kRowValues = 5;

[[noreturn]] void fail(const std::filesystem::path& file, const std::string& what, std::int64_t offset = -1,
                       const std::string& channel = {}) {
  throw hil::RunLogError(
      file.string() + ": " +
          (offset >= 0 ? "the event at byte offset " + std::to_string(offset) + " (channel " + channel + "): "
                       : std::string()) +
          what,
      offset, channel);
}

// True when the event's payload starts with `Message`'s type hash.
template <class Message>
bool hasTypeHash(const hil::LcmLogEvent& event) {
  if (event.data.size() < 8) return false;
  std::uint64_t h = 0;
  for (std::size_t i = 0; i < 8; ++i) h = (h << 8) | event.data[i];
  return static_cast<std::int64_t>(h) == Message::getHash();
}

// Logs written before the chamber pressures were logged carry the earlier layouts (the _v1_t
// types): read as the current ones without pressures.
fullarm_lcm::ident_experiment_t decodeExperiment(const hil::LcmLogEvent& event, const std::filesystem::path& file,
                                                 bool& earlier_layout) {
  earlier_layout = hasTypeHash<fullarm_lcm::ident_experiment_v1_t>(event);
  if (!earlier_layout) return hil::decodeEvent<fullarm_lcm::ident_experiment_t>(event, file);
  const auto v1 = hil::decodeEvent<fullarm_lcm::ident_experiment_v1_t>(event, file);
  fullarm_lcm::ident_experiment_t h{};
  h.utime = v1.utime;
  h.fullarm_version = v1.fullarm_version;
  h.command_line = v1.command_line;
  h.source = v1.source;
  h.joint = v1.joint;
  h.sample_period_s = v1.sample_period_s;
  h.num_held = v1.num_held;
  h.held_joints = v1.held_joints;
  h.num_pressures = 0;
  return h;
}

fullarm_lcm::ident_sample_t decodeSample(const hil::LcmLogEvent& event, const std::filesystem::path& file,
                                         bool earlier_layout) {
  if (!earlier_layout) return hil::decodeEvent<fullarm_lcm::ident_sample_t>(event, file);
  const auto v1 = hil::decodeEvent<fullarm_lcm::ident_sample_v1_t>(event, file);
  fullarm_lcm::ident_sample_t s{};
  s.utime = v1.utime;
  s.seq = v1.seq;
  s.t_s = v1.t_s;
  s.excitation_v = v1.excitation_v;
  s.command_v = v1.command_v;
  s.q_rad = v1.q_rad;
  s.tau_measured_nm = v1.tau_measured_nm;
  s.num_held = v1.num_held;
  s.held_q_rad = v1.held_q_rad;
  s.num_pressures = 0;
  return s;
}

std::int64_t microseconds(double t_s) {
  return static_cast<std::int64_t>(std::llround(t_s * 1e6));
}

}  // namespace

bool isLcmLog(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) fail(file, "cannot be opened");
  std::array<unsigned char, 4> magic{};
  in.read(reinterpret_cast<char*>(magic.data()), static_cast<std::streamsize>(magic.size()));
  return in.gcount() == 4 && magic == std::array<unsigned char, 4>{0xED, 0xA1, 0xDA, 0x01};
}

void writeExperimentLcmLog(const std::filesystem::path& file, const SignalTable& table, const ExperimentLogInfo& info) {
  std::vector<const std::vector<double>*> columns;
  for (const std::string& name : kExperimentColumns) {
    if (!table.has(name)) throw std::invalid_argument("experiment LCM log: the table has no column " + name);
    columns.push_back(&table.column(name));
  }
  const std::vector<HeldAngle> held = heldAngles(table);
  const bool pressures = table.has(kPressureColumns[0]) || table.has(kPressureColumns[1]);
  std::vector<const std::vector<double>*> pressure_columns;
  if (pressures) {
    for (const std::string& name : kPressureColumns) {
      if (!table.has(name)) {
        throw std::invalid_argument("experiment LCM log: the table has one chamber pressure but no column " + name);
      }
      pressure_columns.push_back(&table.column(name));
    }
  }
  if (table.names.size() != kExperimentColumns.size() + pressure_columns.size() + held.size() ||
      table.columns.size() != table.names.size()) {
    throw std::invalid_argument(
        "experiment LCM log: columns other than the experiment's, the chamber pressures and the held joints' angles "
        "(held_<joint>_rad)");
  }
  if (held.size() > static_cast<std::size_t>(kMaxHeldJoints)) {
    throw std::invalid_argument("experiment LCM log: " + std::to_string(held.size()) + " held joints (at most " +
                                std::to_string(kMaxHeldJoints) + ")");
  }
  std::vector<const std::vector<double>*> held_columns;
  for (const HeldAngle& h : held) held_columns.push_back(&table.column(heldAngleColumn(h.joint)));
  const std::size_t rows = table.rows();
  for (const auto& c : table.columns) {
    if (c.size() != rows) throw std::invalid_argument("experiment LCM log: columns of unequal length");
  }
  // What the reader refuses is not written.
  if (rows == 0) throw std::invalid_argument("experiment LCM log: the table has no rows");
  for (std::size_t c = 0; c < table.columns.size(); ++c) {
    for (std::size_t k = 0; k < rows; ++k) {
      if (!std::isfinite(table.columns[c][k])) {
        throw std::invalid_argument("experiment LCM log: " + table.names[c] + " is not finite at row " +
                                    std::to_string(k + 1));
      }
      if (c == 0 && k > 0 && !(table.columns[0][k] > table.columns[0][k - 1])) {
        throw std::invalid_argument("experiment LCM log: time does not increase at row " + std::to_string(k + 1));
      }
    }
  }
  if (!(std::isfinite(info.sample_period_s) && info.sample_period_s > 0.0)) {
    throw std::invalid_argument("experiment LCM log: sample period " + std::to_string(info.sample_period_s) +
                                " s, expected a positive period");
  }

  // The run log's writer, driven synchronously: no rings, no thread.
  hil::RunLogWriterOptions options;
  options.file = file;
  hil::RunLogWriter log(options);
  const double t0 = rows > 0 ? (*columns[0])[0] : 0.0;
  fullarm_lcm::ident_experiment_t header{};
  header.utime = microseconds(t0);
  header.fullarm_version = FULLARM_VERSION;
  header.command_line = info.command_line;
  header.source = info.source;
  header.joint = info.joint;
  header.sample_period_s = info.sample_period_s;
  header.num_held = static_cast<std::int8_t>(held.size());
  for (const HeldAngle& h : held) header.held_joints.push_back(h.joint);
  header.num_pressures = static_cast<std::int8_t>(pressure_columns.size());
  log.writeMessage(channel::kIdentExperiment, header.utime, header);

  fullarm_lcm::ident_sample_t sample{};
  sample.num_held = header.num_held;
  sample.held_q_rad.resize(held.size());
  sample.num_pressures = header.num_pressures;
  sample.pressure_pa.resize(pressure_columns.size());
  for (std::size_t k = 0; k < rows; ++k) {
    sample.t_s = (*columns[0])[k];
    sample.utime = microseconds(sample.t_s);
    sample.seq = static_cast<std::int64_t>(k);
    sample.excitation_v = (*columns[1])[k];
    sample.command_v = (*columns[2])[k];
    sample.q_rad = (*columns[3])[k];
    sample.tau_measured_nm = (*columns[4])[k];
    for (std::size_t j = 0; j < held.size(); ++j) sample.held_q_rad[j] = (*held_columns[j])[k];
    for (std::size_t j = 0; j < pressure_columns.size(); ++j) sample.pressure_pa[j] = (*pressure_columns[j])[k];
    log.writeMessage(channel::kIdentSample, sample.utime, sample);
    if (k % 1024 == 1023 && !log.error().empty()) break;  // a failed write: the rest would fail too
  }
  log.stop();  // flushes
  // Write errors name the file already; an encoding error names the channel only.
  if (const std::string e = log.error(); !e.empty()) {
    throw hil::RunLogError(e.rfind(file.string(), 0) == 0 ? e : file.string() + ": " + e);
  }
}

ExperimentLcmLog readExperimentLcmLog(const std::filesystem::path& file) {
  hil::LcmLogReader reader(file);
  ExperimentLcmLog out;
  bool have_header = false;
  bool earlier_layout = false;
  fullarm_lcm::ident_experiment_t header{};
  std::int64_t next_seq = 0;
  hil::LcmLogEvent event;
  while (reader.next(event)) {
    if (event.channel == channel::kIdentExperiment) {
      if (have_header)
        fail(file, "a second experiment description: one experiment per log", event.offset, event.channel);
      header = decodeExperiment(event, file, earlier_layout);
      have_header = true;
      if (header.num_held > kMaxHeldJoints) {
        fail(file, "num_held " + std::to_string(header.num_held) + ": expected 0 to " + std::to_string(kMaxHeldJoints),
             event.offset, event.channel);
      }
      if (!(std::isfinite(header.sample_period_s) && header.sample_period_s > 0.0)) {
        fail(file, "sample_period_s " + std::to_string(header.sample_period_s) + ": expected a positive period",
             event.offset, event.channel);
      }
      if (header.joint.empty())
        fail(file, "joint is empty: expected the driven joint's name", event.offset, event.channel);
      if (header.num_pressures != 0 && header.num_pressures != static_cast<std::int8_t>(kPressureColumns.size())) {
        fail(file, "num_pressures " + std::to_string(header.num_pressures) + ": expected 0 or 2 (chambers A and B)",
             event.offset, event.channel);
      }
      out.table.names = kExperimentColumns;
      if (header.num_pressures != 0) {
        out.table.names.insert(out.table.names.end(), kPressureColumns.begin(), kPressureColumns.end());
      }
      for (const std::string& name : header.held_joints) {
        if (!isLoggableJointName(name)) {
          fail(file, "held joint '" + name + "': expected a joint name", event.offset, event.channel);
        }
        const std::string column = heldAngleColumn(name);
        for (const std::string& existing : out.table.names) {
          if (existing == column) fail(file, "held joint '" + name + "' named twice", event.offset, event.channel);
        }
        out.table.names.push_back(column);
      }
      out.table.columns.assign(out.table.names.size(), {});
      out.info.command_line = header.command_line;
      out.info.source = header.source;
      out.info.joint = header.joint;
      out.info.sample_period_s = header.sample_period_s;
      out.info.fullarm_version = header.fullarm_version;
      continue;
    }
    if (event.channel != channel::kIdentSample) {
      ++out.skipped;
      continue;
    }
    if (!have_header) {
      fail(file,
           std::string("a sample before the experiment description: expected ") + channel::kIdentExperiment + " first",
           event.offset, event.channel);
    }
    const auto s = decodeSample(event, file, earlier_layout);
    if (s.seq != next_seq) {
      fail(file,
           "sample seq " + std::to_string(s.seq) + " where " + std::to_string(next_seq) +
               " was expected: " + (s.seq > next_seq ? "samples are missing" : "a sample is repeated or out of order"),
           event.offset, event.channel);
    }
    if (s.num_held != header.num_held) {
      fail(file,
           "sample " + std::to_string(s.seq) + " carries " + std::to_string(s.num_held) +
               " held angles, the description " + std::to_string(header.num_held),
           event.offset, event.channel);
    }
    if (s.num_pressures != header.num_pressures) {
      fail(file,
           "sample " + std::to_string(s.seq) + " carries " + std::to_string(s.num_pressures) +
               " chamber pressures, the description " + std::to_string(header.num_pressures),
           event.offset, event.channel);
    }
    for (std::size_t j = 0; j < s.pressure_pa.size(); ++j) {
      if (!std::isfinite(s.pressure_pa[j])) {
        fail(file,
             "sample " + std::to_string(s.seq) + ": " + kPressureColumns[j] + " is " +
                 std::to_string(s.pressure_pa[j]) + ": expected a finite number",
             event.offset, event.channel);
      }
    }
    auto& c = out.table.columns;
    const std::array<double, kRowValues> values{s.t_s, s.excitation_v, s.command_v, s.q_rad, s.tau_measured_nm};
    for (std::size_t i = 0; i < kRowValues; ++i) {
      if (!std::isfinite(values[i])) {
        fail(file,
             "sample " + std::to_string(s.seq) + ": " + kExperimentColumns[i] + " is " + std::to_string(values[i]) +
                 ": expected a finite number",
             event.offset, event.channel);
      }
    }
    for (std::size_t j = 0; j < s.held_q_rad.size(); ++j) {
      if (!std::isfinite(s.held_q_rad[j])) {
        fail(file,
             "sample " + std::to_string(s.seq) + ": held joint " + header.held_joints[j] + "'s angle is " +
                 std::to_string(s.held_q_rad[j]) + ": expected a finite number",
             event.offset, event.channel);
      }
    }
    if (!c[0].empty() && !(s.t_s > c[0].back())) {
      fail(file,
           "sample " + std::to_string(s.seq) + ": time " + std::to_string(s.t_s) + " s does not follow " +
               std::to_string(c[0].back()) + " s: expected time to increase",
           event.offset, event.channel);
    }
    for (std::size_t i = 0; i < kRowValues; ++i) c[i].push_back(values[i]);
    for (std::size_t j = 0; j < s.pressure_pa.size(); ++j) c[kRowValues + j].push_back(s.pressure_pa[j]);
    const std::size_t held_at = kRowValues + s.pressure_pa.size();
    for (std::size_t j = 0; j < s.held_q_rad.size(); ++j) c[held_at + j].push_back(s.held_q_rad[j]);
    ++next_seq;
  }
  const std::string cut = reader.truncated() ? " (" + reader.warning() + ")" : std::string();
  if (!have_header) {
    fail(file, std::string("no ") + channel::kIdentExperiment + " event: not an identification experiment log" + cut);
  }
  if (next_seq == 0) {
    fail(file, std::string("no ") + channel::kIdentSample + " event: the experiment has no samples" + cut);
  }
  // The description's period is the samples' time step (the fit's uniform time base).
  const auto& t = out.table.columns[0];
  if (t.size() >= 2) {
    const double step = (t.back() - t.front()) / static_cast<double>(t.size() - 1);
    if (std::abs(step - header.sample_period_s) > 1e-6 * header.sample_period_s) {
      fail(file, "the samples come every " + std::to_string(step) + " s, the description says every " +
                     std::to_string(header.sample_period_s) + " s");
    }
  }
  out.warning = reader.warning();
  return out;
}

}  // namespace fullarm::identification
