#include "fullarm/hil/log_records.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace fullarm::hil {
namespace {

int clampCount(int n, int bound) noexcept {
  return std::clamp(n, 0, bound);
}

/// Throws unless 0 <= n <= bound.
void checkCount(const char* type, const char* field, long long n, int bound) {
  if (n < 0 || n > bound) {
    throw RecordError(std::string(type) + "." + field + " = " + std::to_string(n) + ": expected 0 .. " +
                      std::to_string(bound));
  }
}

/// Throws unless the array has exactly n entries.
template <class Vector>
void checkSize(const char* type, const char* field, const Vector& v, long long n) {
  if (static_cast<long long>(v.size()) != n) {
    throw RecordError(std::string(type) + "." + field + " has " + std::to_string(v.size()) +
                      " entries, its count says " + std::to_string(n));
  }
}

template <std::size_t N>
std::vector<double> head(const std::array<double, N>& a, int n) {
  return {a.begin(), a.begin() + n};
}

template <std::size_t N>
void copyHead(const std::vector<double>& v, std::array<double, N>& a) {
  std::copy(v.begin(), v.end(), a.begin());
}

fullarm_lcm::minimum_t toMessage(const MinimumRecord& r) {
  fullarm_lcm::minimum_t m{};
  m.link = static_cast<std::int16_t>(r.link);
  m.object = static_cast<std::int16_t>(r.object);
  m.tri_link = r.tri_link;
  m.tri_object = r.tri_object;
  m.feature_link_kind = r.feature_link_kind;
  m.feature_link_index = r.feature_link_index;
  m.feature_object_kind = r.feature_object_kind;
  m.feature_object_index = r.feature_object_index;
  std::copy(r.p_link_m.begin(), r.p_link_m.end(), m.p_link_m);
  std::copy(r.p_object_m.begin(), r.p_object_m.end(), m.p_object_m);
  m.distance_m = r.distance_m;
  std::copy(r.u_world_unit.begin(), r.u_world_unit.end(), m.u_world_unit);
  m.previous_distance_m = r.previous_distance_m;
  return m;
}

MinimumRecord fromMessage(const fullarm_lcm::minimum_t& m) {
  if (m.feature_link_kind < 0 || m.feature_link_kind > 2 || m.feature_object_kind < 0 || m.feature_object_kind > 2) {
    throw RecordError("minimum_t.feature_*_kind = " + std::to_string(m.feature_link_kind) + ", " +
                      std::to_string(m.feature_object_kind) + ": expected 0 (face), 1 (edge) or 2 (vertex)");
  }
  MinimumRecord r;
  r.link = m.link;
  r.object = m.object;
  r.tri_link = m.tri_link;
  r.tri_object = m.tri_object;
  r.feature_link_kind = m.feature_link_kind;
  r.feature_link_index = m.feature_link_index;
  r.feature_object_kind = m.feature_object_kind;
  r.feature_object_index = m.feature_object_index;
  std::copy(m.p_link_m, m.p_link_m + 3, r.p_link_m.begin());
  std::copy(m.p_object_m, m.p_object_m + 3, r.p_object_m.begin());
  r.distance_m = m.distance_m;
  std::copy(m.u_world_unit, m.u_world_unit + 3, r.u_world_unit.begin());
  r.previous_distance_m = m.previous_distance_m;
  return r;
}

}  // namespace

void SupervisorEventRecord::setMessage(std::string_view text) noexcept {
  const std::size_t n = std::min<std::size_t>(text.size(), kMaxEventMessageChars);
  std::memcpy(message.data(), text.data(), n);
  message[n] = '\0';
}

std::string_view SupervisorEventRecord::messageView() const noexcept {
  return {message.data(), ::strnlen(message.data(), message.size())};
}

MinimumRecord toMinimumRecord(const haptics::LocalMinimum& m) noexcept {
  MinimumRecord r;
  r.link = m.link;
  r.object = m.object;
  r.tri_link = m.tri_link;
  r.tri_object = m.tri_object;
  r.feature_link_kind = static_cast<std::int8_t>(m.feature_link.kind);
  r.feature_link_index = m.feature_link.index;
  r.feature_object_kind = static_cast<std::int8_t>(m.feature_object.kind);
  r.feature_object_index = m.feature_object.index;
  for (int i = 0; i < 3; ++i) {
    r.p_link_m[i] = m.p_L[i];
    r.p_object_m[i] = m.p_O[i];
    r.u_world_unit[i] = m.u_W[i];
  }
  r.distance_m = m.distance_m;
  r.previous_distance_m = m.previous_distance_m;
  return r;
}

haptics::LocalMinimum toLocalMinimum(const MinimumRecord& r) noexcept {
  haptics::LocalMinimum m;
  m.link = r.link;
  m.object = r.object;
  m.tri_link = r.tri_link;
  m.tri_object = r.tri_object;
  m.feature_link = {static_cast<haptics::FeatureKind>(r.feature_link_kind), r.feature_link_index};
  m.feature_object = {static_cast<haptics::FeatureKind>(r.feature_object_kind), r.feature_object_index};
  for (int i = 0; i < 3; ++i) {
    m.p_L[i] = r.p_link_m[i];
    m.p_O[i] = r.p_object_m[i];
    m.u_W[i] = r.u_world_unit[i];
  }
  m.distance_m = r.distance_m;
  m.previous_distance_m = r.previous_distance_m;
  return m;
}

void fillMinima(std::span<const haptics::LocalMinimum> minima, MinimaSetRecord& set) noexcept {
  const std::size_t n = minima.size();
  const std::size_t cap = static_cast<std::size_t>(kMaxMinimaPerSet);
  if (n <= cap) {
    for (std::size_t i = 0; i < n; ++i) set.minima[i] = toMinimumRecord(minima[i]);
    set.num_minima = static_cast<int>(n);
    set.num_minima_dropped = 0;
    return;
  }
  // Keep the kMaxMinimaPerSet closest, in their original order: the cap-th smallest distance
  // (ties by index) is the cut; a bounded selection without allocation, O(n * cap).
  // Candidate i is kept if fewer than cap minima come before it in (distance, index) order.
  int kept = 0;
  for (std::size_t i = 0; i < n && kept < kMaxMinimaPerSet; ++i) {
    std::size_t before = 0;
    const double di = minima[i].distance_m;
    for (std::size_t j = 0; j < n && before < cap; ++j) {
      const double dj = minima[j].distance_m;
      if (dj < di || (dj == di && j < i) || (std::isnan(di) && !std::isnan(dj))) ++before;
    }
    if (before < cap) set.minima[static_cast<std::size_t>(kept++)] = toMinimumRecord(minima[i]);
  }
  set.num_minima = kept;
  set.num_minima_dropped = static_cast<int>(n) - kept;
}

fullarm_lcm::joint_state_t toMessage(const JointStateRecord& r) {
  fullarm_lcm::joint_state_t m{};
  const int n = clampCount(r.num_joints, kMaxRecordJoints);
  m.utime = r.utime_us;
  m.seq = r.seq;
  m.tick = r.tick;
  m.num_joints = static_cast<std::int8_t>(n);
  m.q_rad = head(r.q_rad, n);
  m.tau_measured_nm = head(r.tau_measured_nm, n);
  m.valve_command_v = head(r.valve_command_v, n);
  m.input_flags = static_cast<std::int32_t>(r.input_flags);
  return m;
}

fullarm_lcm::valve_command_t toMessage(const ValveCommandRecord& r) {
  fullarm_lcm::valve_command_t m{};
  const int n = clampCount(r.num_valves, kMaxRecordJoints);
  m.utime = r.utime_us;
  m.seq = r.seq;
  m.tick = r.tick;
  m.num_valves = static_cast<std::int8_t>(n);
  m.valve_command_v = head(r.valve_command_v, n);
  m.safe_output = r.safe_output ? 1 : 0;
  return m;
}

fullarm_lcm::haptic_status_t toMessage(const HapticStatusRecord& r) {
  fullarm_lcm::haptic_status_t m{};
  const int nj = clampCount(r.num_joints, kMaxRecordJoints);
  const int nl = clampCount(r.num_links, kMaxRecordJoints);
  m.utime = r.utime_us;
  m.seq = r.seq;
  m.tick = r.tick;
  m.mode = static_cast<std::int8_t>(r.mode);
  m.active_springs = static_cast<std::int16_t>(std::clamp(r.active_springs, 0, 32767));
  m.num_minima_tracked = static_cast<std::int16_t>(std::clamp(r.num_minima_tracked, 0, 32767));
  m.minima_set_id = r.minima_set_id;
  m.contact_scale = r.contact_scale;
  m.num_joints = static_cast<std::int8_t>(nj);
  m.tau_contact_nm = head(r.tau_contact_nm, nj);
  m.num_links = static_cast<std::int8_t>(nl);
  m.links.resize(static_cast<std::size_t>(nl));
  for (int i = 0; i < nl; ++i) {
    const LinkContactStatus& s = r.links[static_cast<std::size_t>(i)];
    fullarm_lcm::link_contact_t& l = m.links[static_cast<std::size_t>(i)];
    std::copy(s.force_world_n.begin(), s.force_world_n.end(), l.force_world_n);
    l.min_distance_m = s.min_distance_m;
    l.depth_m = s.depth_m;
    l.in_contact = s.in_contact ? 1 : 0;
    l.penetrating = s.penetrating ? 1 : 0;
    l.contact_duration_s = s.contact_duration_s;
    l.total_penetration_s = s.total_penetration_s;
  }
  return m;
}

fullarm_lcm::supervisor_event_t toMessage(const SupervisorEventRecord& r) {
  fullarm_lcm::supervisor_event_t m{};
  m.utime = r.utime_us;
  m.seq = r.seq;
  m.tick = r.tick;
  m.cause_code = static_cast<std::int16_t>(std::clamp(r.cause_code, -32768, 32767));
  m.severity = static_cast<std::int8_t>(r.severity);
  m.joint = static_cast<std::int8_t>(std::clamp(r.joint, -1, 127));
  m.value = r.value;
  m.limit = r.limit;
  m.message = std::string(r.messageView());
  return m;
}

JointStateRecord fromMessage(const fullarm_lcm::joint_state_t& m) {
  checkCount("joint_state_t", "num_joints", m.num_joints, kMaxRecordJoints);
  checkSize("joint_state_t", "q_rad", m.q_rad, m.num_joints);
  checkSize("joint_state_t", "tau_measured_nm", m.tau_measured_nm, m.num_joints);
  checkSize("joint_state_t", "valve_command_v", m.valve_command_v, m.num_joints);
  JointStateRecord r;
  r.utime_us = m.utime;
  r.seq = m.seq;
  r.tick = m.tick;
  r.num_joints = m.num_joints;
  copyHead(m.q_rad, r.q_rad);
  copyHead(m.tau_measured_nm, r.tau_measured_nm);
  copyHead(m.valve_command_v, r.valve_command_v);
  r.input_flags = static_cast<std::uint32_t>(m.input_flags);
  return r;
}

ValveCommandRecord fromMessage(const fullarm_lcm::valve_command_t& m) {
  checkCount("valve_command_t", "num_valves", m.num_valves, kMaxRecordJoints);
  checkSize("valve_command_t", "valve_command_v", m.valve_command_v, m.num_valves);
  ValveCommandRecord r;
  r.utime_us = m.utime;
  r.seq = m.seq;
  r.tick = m.tick;
  r.num_valves = m.num_valves;
  copyHead(m.valve_command_v, r.valve_command_v);
  r.safe_output = m.safe_output != 0;
  return r;
}

HapticStatusRecord fromMessage(const fullarm_lcm::haptic_status_t& m) {
  checkCount("haptic_status_t", "num_joints", m.num_joints, kMaxRecordJoints);
  checkCount("haptic_status_t", "num_links", m.num_links, kMaxRecordJoints);
  checkSize("haptic_status_t", "tau_contact_nm", m.tau_contact_nm, m.num_joints);
  checkSize("haptic_status_t", "links", m.links, m.num_links);
  if (m.mode != 0 && m.mode != 1) {
    throw RecordError("haptic_status_t.mode = " + std::to_string(m.mode) + ": expected 0 (full-arm) or 1 (hand-only)");
  }
  HapticStatusRecord r;
  r.utime_us = m.utime;
  r.seq = m.seq;
  r.tick = m.tick;
  r.mode = static_cast<LoggedMode>(m.mode);
  r.active_springs = m.active_springs;
  r.num_minima_tracked = m.num_minima_tracked;
  r.minima_set_id = m.minima_set_id;
  r.contact_scale = m.contact_scale;
  r.num_joints = m.num_joints;
  copyHead(m.tau_contact_nm, r.tau_contact_nm);
  r.num_links = m.num_links;
  for (int i = 0; i < m.num_links; ++i) {
    const fullarm_lcm::link_contact_t& l = m.links[static_cast<std::size_t>(i)];
    LinkContactStatus& s = r.links[static_cast<std::size_t>(i)];
    std::copy(l.force_world_n, l.force_world_n + 3, s.force_world_n.begin());
    s.min_distance_m = l.min_distance_m;
    s.depth_m = l.depth_m;
    s.in_contact = l.in_contact != 0;
    s.penetrating = l.penetrating != 0;
    s.contact_duration_s = l.contact_duration_s;
    s.total_penetration_s = l.total_penetration_s;
  }
  return r;
}

SupervisorEventRecord fromMessage(const fullarm_lcm::supervisor_event_t& m) {
  if (m.severity < 0 || m.severity > 3) {
    throw RecordError("supervisor_event_t.severity = " + std::to_string(m.severity) + ": expected 0 .. 3");
  }
  SupervisorEventRecord r;
  r.utime_us = m.utime;
  r.seq = m.seq;
  r.tick = m.tick;
  r.cause_code = m.cause_code;
  r.severity = static_cast<EventSeverity>(m.severity);
  r.joint = m.joint;
  r.value = m.value;
  r.limit = m.limit;
  r.setMessage(m.message);
  return r;
}

int fragmentCount(int num_minima) noexcept {
  const int n = clampCount(num_minima, kMaxMinimaPerSet);
  return n == 0 ? 1 : (n + kMaxMinimaPerFragment - 1) / kMaxMinimaPerFragment;
}

fullarm_lcm::minima_set_t toFragment(const MinimaSetRecord& set, int index, std::int64_t seq) {
  const int total = clampCount(set.num_minima, kMaxMinimaPerSet);
  const int count = fragmentCount(total);
  if (index < 0 || index >= count) {
    throw RecordError("minima set " + std::to_string(set.set_id) + ": fragment " + std::to_string(index) +
                      " requested, expected 0 .. " + std::to_string(count - 1));
  }
  const int first = index * kMaxMinimaPerFragment;
  const int n = std::min(kMaxMinimaPerFragment, total - first);
  const int nj = clampCount(set.num_joints, kMaxRecordJoints);
  fullarm_lcm::minima_set_t m{};
  m.utime = set.utime_us;
  m.seq = seq;
  m.set_id = set.set_id;
  m.fragment_index = static_cast<std::int16_t>(index);
  m.fragment_count = static_cast<std::int16_t>(count);
  m.num_minima_total = static_cast<std::int16_t>(total);
  m.first_minimum_index = static_cast<std::int16_t>(first);
  m.num_minima_dropped = static_cast<std::int16_t>(std::clamp(set.num_minima_dropped, 0, 32767));
  m.computed_tick = set.computed_tick;
  m.computed_utime = set.computed_utime_us;
  m.adopted_tick = set.adopted_tick;
  m.num_joints = static_cast<std::int8_t>(nj);
  m.q_rad = head(set.q_rad, nj);
  m.num_minima = static_cast<std::int16_t>(n);
  m.minima.reserve(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) m.minima.push_back(toMessage(set.minima[static_cast<std::size_t>(first + i)]));
  return m;
}

int checkFragment(const fullarm_lcm::minima_set_t& f) {
  const std::string where =
      "minima_set_t (set " + std::to_string(f.set_id) + ", fragment " + std::to_string(f.fragment_index) + ")";
  checkCount(where.c_str(), "num_minima_total", f.num_minima_total, kMaxMinimaPerSet);
  checkCount(where.c_str(), "num_joints", f.num_joints, kMaxRecordJoints);
  checkCount(where.c_str(), "num_minima", f.num_minima, kMaxMinimaPerFragment);
  checkSize(where.c_str(), "q_rad", f.q_rad, f.num_joints);
  checkSize(where.c_str(), "minima", f.minima, f.num_minima);
  // The fragment's place in its set under a layout of `per` minima per fragment, or "" when it
  // fits that layout.
  auto mismatch = [&f](int per) -> std::string {
    const int total = f.num_minima_total;
    const int count = total == 0 ? 1 : (total + per - 1) / per;
    if (f.fragment_count != count) {
      return "fragment_count = " + std::to_string(f.fragment_count) + ", expected " + std::to_string(count) + " for " +
             std::to_string(total) + " minima";
    }
    if (f.fragment_index < 0 || f.fragment_index >= count) {
      return "fragment_index = " + std::to_string(f.fragment_index) + " outside 0 .. " + std::to_string(count - 1);
    }
    const int first = f.fragment_index * per;
    const int expected_n = std::min(per, total - first);
    if (f.first_minimum_index != first || f.num_minima != expected_n) {
      return "carries minima " + std::to_string(f.first_minimum_index) + " .. +" + std::to_string(f.num_minima) +
             ", expected " + std::to_string(first) + " .. +" + std::to_string(expected_n);
    }
    return {};
  };
  int per = kMaxMinimaPerFragment;
  const std::string current = mismatch(kMaxMinimaPerFragment);
  if (!current.empty()) {
    if (!mismatch(kLegacyMinimaPerFragment).empty()) throw RecordError(where + ": " + current);
    per = kLegacyMinimaPerFragment;
  }
  for (const fullarm_lcm::minimum_t& m : f.minima) (void)fromMessage(m);
  return per;
}

bool MinimaSetAssembler::add(const fullarm_lcm::minima_set_t& f) {
  const int per = checkFragment(f);
  const std::string where =
      "minima_set_t (set " + std::to_string(f.set_id) + ", fragment " + std::to_string(f.fragment_index) + ")";
  const int count = f.fragment_count;  // checked against the total in the fragment's layout
  const int first = f.first_minimum_index;
  if (building_ && f.set_id < building_id_) {
    // An older set, unless its producer restarted its numbering (SequenceTracker's rules, by
    // set: a jump back beyond kRestartJump, or kRestartRun older sets in a row, increasing).
    if (older_run_ == 0 || f.set_id < older_last_id_) {
      older_run_ = 1;
    } else if (f.set_id > older_last_id_) {
      ++older_run_;  // another fragment of the same older set leaves the run as it is
    }
    older_last_id_ = f.set_id;
    std::int64_t back = 0;  // a difference beyond int64 (a damaged id) is far back too
    const bool restart =
        __builtin_sub_overflow(building_id_, f.set_id, &back) || back > kSetRestartJump || older_run_ >= kSetRestartRun;
    if (!restart) {
      ++ignored_;
      return false;
    }
    ++restarts_;
    building_ = false;  // begins the restarted producer's set below
  }
  if (f.set_id >= building_id_) older_run_ = 0;
  if (!building_ || f.set_id != building_id_) {
    if (building_ && have_count_ < expected_fragments_) ++abandoned_;
    building_ = true;
    building_id_ = f.set_id;
    expected_fragments_ = count;
    fragment_size_ = per;
    have_.fill(false);
    have_count_ = 0;
    set_.utime_us = f.utime;
    set_.seq = f.seq;
    set_.set_id = f.set_id;
    set_.computed_tick = f.computed_tick;
    set_.computed_utime_us = f.computed_utime;
    set_.adopted_tick = f.adopted_tick;
    set_.num_joints = f.num_joints;
    set_.q_rad.fill(0.0);
    copyHead(f.q_rad, set_.q_rad);
    set_.num_minima = f.num_minima_total;
    set_.num_minima_dropped = f.num_minima_dropped;
  } else {
    if (have_count_ == expected_fragments_ || have_[static_cast<std::size_t>(f.fragment_index)]) {
      ++ignored_;  // the set is complete already, or this fragment came twice
      return false;
    }
    const bool same = per == fragment_size_ && set_.computed_tick == f.computed_tick &&
                      set_.adopted_tick == f.adopted_tick && set_.num_minima == f.num_minima_total &&
                      set_.num_joints == f.num_joints &&
                      std::equal(f.q_rad.begin(), f.q_rad.end(), set_.q_rad.begin(),
                                 [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; });
    if (!same) throw RecordError(where + ": its header disagrees with the set's other fragments");
  }
  for (int i = 0; i < f.num_minima; ++i) {
    set_.minima[static_cast<std::size_t>(first + i)] = fromMessage(f.minima[static_cast<std::size_t>(i)]);
  }
  have_[static_cast<std::size_t>(f.fragment_index)] = true;
  ++have_count_;
  return have_count_ == expected_fragments_;
}

}  // namespace fullarm::hil
