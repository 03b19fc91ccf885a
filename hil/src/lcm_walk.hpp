#pragma once
/// @file
/// A cursor over an encoded LCM message, for the checks that run before lcm-gen's C++ decoder
/// reads a message from a file or the network (lcm_layout.cpp, lcm_io.cpp). Each step checks
/// that its bytes are there and its value in range. The first failure is kept, and tells
/// whether the payload ended inside a field (truncated) or a field held a value no encoder
/// writes (malformed); the steps after it do nothing, so a layout is walked as a plain sequence
/// of steps and judged once by finish().

#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "fullarm/hil/lcm_transport.hpp"

namespace fullarm::hil::detail {

/// Its verdicts are the decoders' own: DecodeStatus kOk, kTruncated or kMalformed.
class LcmWalk {
 public:
  /// Starts past the 8-byte type hash; a message shorter than the hash is truncated.
  explicit LcmWalk(std::span<const std::uint8_t> bytes) noexcept : bytes_(bytes) {
    if (bytes_.size() < kHashBytes) outcome_ = DecodeStatus::kTruncated;
  }

  /// Fixed-size fields of `n` bytes in all.
  void skip(std::size_t n) noexcept {
    if (!ok()) return;
    if (bytes_.size() - at_ < n) {
      outcome_ = DecodeStatus::kTruncated;
      return;
    }
    at_ += n;
  }

  /// One string: an int32 length that counts the terminating NUL, then the characters and the
  /// NUL. A length below 1 is malformed (the generated decoder would copy `length - 1`
  /// characters); so is one of fewer than `min_chars` or more than `max_chars` characters.
  void string(std::size_t min_chars = 0, std::size_t max_chars = std::numeric_limits<std::size_t>::max()) noexcept {
    std::int64_t len = 0;
    if (!signedBigEndian(4, len)) return;
    if (len < 1) {
      outcome_ = DecodeStatus::kMalformed;
      return;
    }
    const auto n = static_cast<std::uint64_t>(len);  // with the NUL
    if (n > bytes_.size() - at_) {
      outcome_ = DecodeStatus::kTruncated;
    } else if (n - 1 < min_chars || n - 1 > max_chars) {
      outcome_ = DecodeStatus::kMalformed;
    } else {
      at_ += static_cast<std::size_t>(n);
    }
  }

  /// `n` strings, each as string().
  void strings(std::int64_t n, std::size_t min_chars = 0,
               std::size_t max_chars = std::numeric_limits<std::size_t>::max()) noexcept {
    for (std::int64_t k = 0; k < n && ok(); ++k) string(min_chars, max_chars);
  }

  /// An array count of `width` bytes (int8_t or int16_t), within [0, max]. Returns it, or 0
  /// once the walk has failed.
  [[nodiscard]] std::int64_t count(std::size_t width,
                                   std::int64_t max = std::numeric_limits<std::int64_t>::max()) noexcept {
    std::int64_t n = 0;
    if (!signedBigEndian(width, n)) return 0;
    if (n < 0 || n > max) {
      outcome_ = DecodeStatus::kMalformed;
      return 0;
    }
    return n;
  }

  /// The walk's verdict once every field was walked: the first failure, or malformed when
  /// bytes are left over (a field the walk does not know of is not passed unchecked).
  [[nodiscard]] DecodeStatus finish() const noexcept {
    if (!ok()) return outcome_;
    return at_ == bytes_.size() ? DecodeStatus::kOk : DecodeStatus::kMalformed;
  }

 private:
  static constexpr std::size_t kHashBytes = 8;

  [[nodiscard]] bool ok() const noexcept { return outcome_ == DecodeStatus::kOk; }
  bool signedBigEndian(std::size_t width, std::int64_t& out) noexcept {
    if (!ok()) return false;
    if (bytes_.size() - at_ < width) {
      outcome_ = DecodeStatus::kTruncated;
      return false;
    }
    std::uint64_t v = 0;
    for (std::size_t i = 0; i < width; ++i) v = (v << 8) | bytes_[at_ + i];
    at_ += width;
    const std::uint64_t sign = std::uint64_t{1} << (8 * width - 1);
    out = (v & sign) != 0 ? static_cast<std::int64_t>(v) - static_cast<std::int64_t>(sign << 1)
                          : static_cast<std::int64_t>(v);
    return true;
  }

  std::span<const std::uint8_t> bytes_;
  std::size_t at_ = kHashBytes;
  DecodeStatus outcome_ = DecodeStatus::kOk;
};

}  // namespace fullarm::hil::detail
