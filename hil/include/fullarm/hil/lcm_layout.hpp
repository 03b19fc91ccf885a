#pragma once
/// @file
/// The string lengths of an encoded LCM message, checked before lcm-gen's C++ decoder reads it.
/// That decoder trusts a string's int32 length (which counts the terminating NUL) after checking
/// only that it does not run past the payload: it then copies `length - 1` characters. A length
/// of 0 or below makes that count huge and the copy throws, but for INT32_MIN `length - 1`
/// overflows to 2^31 - 1 and the copy reads far past the payload. A type with strings that is read
/// from a file or the network gets a walk of its layout here; the others need none.
/// `tests/hil/lcm_layout_test.cpp` checks that every type with a string in `hil/lcm/` has one.

#include <cstdint>
#include <span>

#include "fullarm_lcm/ident_experiment_t.hpp"
#include "fullarm_lcm/ident_experiment_v1_t.hpp"
#include "fullarm_lcm/run_header_t.hpp"
#include "fullarm_lcm/supervisor_event_t.hpp"

namespace fullarm::hil {

/// True when every string of the encoded message `bytes` (its 8-byte type hash first) has a
/// length of at least 1 that ends inside `bytes`, every array count on the way is not negative,
/// and the last field ends at the end of `bytes`. A false message must not be given to the
/// generated decoder.
[[nodiscard]] bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                                          const fullarm_lcm::run_header_t* type) noexcept;
[[nodiscard]] bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                                          const fullarm_lcm::supervisor_event_t* type) noexcept;
[[nodiscard]] bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                                          const fullarm_lcm::ident_experiment_t* type) noexcept;
[[nodiscard]] bool stringLengthsInPayload(std::span<const std::uint8_t> bytes,
                                          const fullarm_lcm::ident_experiment_v1_t* type) noexcept;
/// Types without strings: nothing to check.
template <class Message>
[[nodiscard]] constexpr bool stringLengthsInPayload(std::span<const std::uint8_t> /*bytes*/,
                                                    const Message* /*type*/) noexcept {
  return true;
}

}  // namespace fullarm::hil
