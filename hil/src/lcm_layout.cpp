#include "fullarm/hil/lcm_layout.hpp"

#include "lcm_walk.hpp"

namespace fullarm::hil {

using detail::LcmWalk;

bool stringLengthsInPayload(std::span<const std::uint8_t> bytes, const fullarm_lcm::run_header_t* /*type*/) noexcept {
  // utime, seq, wall_utime; fullarm_version, command_line, io, clock, mode; seed, tick_period_us;
  // num_files and the files (role, path, sha256); num_parameters and the parameters (key, value).
  LcmWalk w(bytes);
  w.skip(24);
  w.strings(5);
  w.skip(12);
  w.strings(3 * w.count(2));
  w.strings(2 * w.count(2));
  return w.finish() == DecodeStatus::kOk;
}

bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                            const fullarm_lcm::supervisor_event_t* /*type*/) noexcept {
  // utime, seq, tick; cause_code; severity, joint; value, limit; message.
  LcmWalk w(bytes);
  w.skip(24 + 2 + 2 + 16);
  w.string();
  return w.finish() == DecodeStatus::kOk;
}

namespace {

// An identification experiment's description: utime; fullarm_version, command_line, source,
// joint; sample_period_s; num_held and the names; then num_pressures (not in the earlier layout).
bool experimentLayout(std::span<const std::uint8_t> bytes, bool with_pressures) noexcept {
  LcmWalk w(bytes);
  w.skip(8);
  w.strings(4);
  w.skip(8);
  w.strings(w.count(1));
  if (with_pressures) w.skip(1);
  return w.finish() == DecodeStatus::kOk;
}

}  // namespace

bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                            const fullarm_lcm::ident_experiment_t* /*type*/) noexcept {
  return experimentLayout(bytes, true);
}

bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                            const fullarm_lcm::ident_experiment_v1_t* /*type*/) noexcept {
  return experimentLayout(bytes, false);
}

}  // namespace fullarm::hil
