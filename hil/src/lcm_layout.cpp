#include "fullarm/hil/lcm_layout.hpp"

#include <cstddef>

namespace fullarm::hil {
namespace {

/// A cursor over an encoded message, past its type hash.
class Walk {
 public:
  explicit Walk(std::span<const std::uint8_t> bytes) noexcept : bytes_(bytes) {}

  /// Fixed-size fields of `n` bytes in all.
  bool skip(std::size_t n) noexcept {
    if (bytes_.size() - at_ < n) return false;
    at_ += n;
    return true;
  }
  /// One string: an int32 length >= 1 (with the NUL) whose characters end inside the payload.
  bool string() noexcept {
    std::int64_t len = 0;
    if (!signedBigEndian(4, len)) return false;
    if (len < 1 || static_cast<std::uint64_t>(len) > bytes_.size() - at_) return false;
    at_ += static_cast<std::size_t>(len);
    return true;
  }
  /// `n` strings.
  bool strings(std::int64_t n) noexcept {
    for (std::int64_t k = 0; k < n; ++k) {
      if (!string()) return false;
    }
    return true;
  }
  /// An array count of `width` bytes (int8_t or int16_t): not negative.
  bool count(std::size_t width, std::int64_t& n) noexcept { return signedBigEndian(width, n) && n >= 0; }
  [[nodiscard]] bool started() const noexcept { return bytes_.size() >= 8; }
  /// The walk ended at the payload's end: a field the walk does not know of (a layout that
  /// changed) is not passed unchecked.
  [[nodiscard]] bool done() const noexcept { return at_ == bytes_.size(); }

 private:
  bool signedBigEndian(std::size_t width, std::int64_t& out) noexcept {
    if (bytes_.size() - at_ < width) return false;
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < width; ++i) v = (v << 8) | bytes_[at_ + i];
    at_ += width;
    const std::uint64_t sign = std::uint64_t{1} << (8 * width - 1);
    out = (v & sign) != 0 ? static_cast<std::int64_t>(v) - static_cast<std::int64_t>(sign << 1)
                          : static_cast<std::int64_t>(v);
    return true;
  }

  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = 8;  // the type hash
};

}  // namespace

bool stringLengthsInPayload(std::span<const std::uint8_t> bytes, const fullarm_lcm::run_header_t* /*type*/) noexcept {
  // utime, seq, wall_utime; fullarm_version, command_line, io, clock, mode; seed, tick_period_us;
  // num_files and the files (role, path, sha256); num_parameters and the parameters (key, value).
  Walk w(bytes);
  std::int64_t files = 0;
  std::int64_t parameters = 0;
  return w.started() && w.skip(24) && w.strings(5) && w.skip(12) && w.count(2, files) && w.strings(3 * files) &&
         w.count(2, parameters) && w.strings(2 * parameters) && w.done();
}

bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                            const fullarm_lcm::supervisor_event_t* /*type*/) noexcept {
  // utime, seq, tick; cause_code; severity, joint; value, limit; message.
  Walk w(bytes);
  return w.started() && w.skip(24 + 2 + 2 + 16) && w.string() && w.done();
}

bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                            const fullarm_lcm::ident_experiment_t* /*type*/) noexcept {
  // utime; fullarm_version, command_line, source, joint; sample_period_s; num_held and the names.
  Walk w(bytes);
  std::int64_t held = 0;
  return w.started() && w.skip(8) && w.strings(4) && w.skip(8) && w.count(1, held) && w.strings(held) && w.done();
}

}  // namespace fullarm::hil
