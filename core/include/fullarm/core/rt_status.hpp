#pragma once
/// @file
/// The one status type of the real-time path: what an @rt function that can fail returns or
/// records in its data object. A code (the first cause), the fault bits seen since the last
/// clear (latched), and a message with static storage, so recording a fault never allocates.
///
/// Two contracts of the real-time path, as the headers state them:
///  - `@rt`: noexcept, allocates nothing, takes no lock, does no I/O or system call, and has a
///    bounded run time (docs/architecture.md, "House style"). Only such a function belongs on the 1 kHz tick.
///  - "Allocation-free, unbounded time": noexcept, allocates nothing, takes no lock, does no I/O
///    or system call, but its run time depends on the solution (an adaptive integrator's step:
///    ArmPlant::step, RosenbrockIntegrator::advance, CVODES), bounded only by a step budget that
///    fails the call when spent. Fit for a simulation loop and for the simulated hardware of a
///    lockstep run, not for the hard-real-time tick. Its allocation tests stay.

#include <cstdint>

namespace fullarm::core {

/// The first cause of a non-ok status.
enum class RtCode : std::uint8_t {
  kOk = 0,
  kNotConfigured,  ///< used before it was configured or reset
  kBadInput,       ///< an input is unusable (non-finite, out of range, too many, bad index)
  kBadState,       ///< the internal state became unusable (non-finite)
  kSolverFailure,  ///< a numerical solver gave up (step too small, too many steps, no convergence)
};

/// Fault bits (OR-ed in RtStatus::faults). Each module sets the bits that describe its faults.
enum RtFault : std::uint32_t {
  kFaultNone = 0,
  kFaultNonFiniteInput = 1u << 0,  ///< an input was NaN or infinite
  kFaultNonFiniteState = 1u << 1,  ///< the internal state became NaN or infinite
  kFaultNotConfigured = 1u << 2,   ///< used before configuration or reset
  kFaultCapacity = 1u << 3,        ///< more items than the preallocated capacity
  kFaultBadIndex = 1u << 4,        ///< an index out of range (a link, a joint)
  kFaultTooManySteps = 1u << 5,    ///< an integrator hit its step budget
  kFaultStepTooSmall = 1u << 6,    ///< an integrator's step fell below its minimum
  kFaultSolver = 1u << 7,          ///< another solver failure (CVODES, a linear solve)
  kFaultOutOfRange = 1u << 8,      ///< a finite input outside its valid range (a non-positive period)
};

/// Status of a real-time computation. Trivially copyable; the message is a string literal.
struct RtStatus {
  RtCode code = RtCode::kOk;
  std::uint32_t faults = kFaultNone;
  const char* message = "ok";  ///< static storage: never freed, never owned

  [[nodiscard]] constexpr bool ok() const noexcept { return code == RtCode::kOk; }
  [[nodiscard]] constexpr bool has(std::uint32_t fault) const noexcept { return (faults & fault) != 0; }

  /// Records a fault: the bits are OR-ed in; the code and message keep the first cause. @rt
  constexpr void raise(RtCode c, std::uint32_t fault, const char* what) noexcept {
    faults |= fault;
    if (code == RtCode::kOk) {
      code = c;
      message = what;
    }
  }
  /// Back to ok. @rt
  constexpr void clear() noexcept { *this = RtStatus{}; }

  /// A status with one fault. @rt
  [[nodiscard]] static constexpr RtStatus fault(RtCode c, std::uint32_t bits, const char* what) noexcept {
    RtStatus s;
    s.raise(c, bits, what);
    return s;
  }
};

/// Name of a code ("ok", "not configured", ...). @rt
[[nodiscard]] constexpr const char* rtCodeName(RtCode code) noexcept {
  switch (code) {
    case RtCode::kOk:
      return "ok";
    case RtCode::kNotConfigured:
      return "not configured";
    case RtCode::kBadInput:
      return "bad input";
    case RtCode::kBadState:
      return "bad state";
    case RtCode::kSolverFailure:
      return "solver failure";
  }
  return "unknown";
}

}  // namespace fullarm::core
