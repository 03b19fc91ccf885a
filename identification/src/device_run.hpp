#pragma once
// What the experiment and the static holds share when they drive an IoDevice: the device
// deactivated however the run ends, reads preceded by the caller's pacing, and the blend that
// moves a hold target.

#include <cmath>
#include <functional>
#include <numbers>
#include <string>

#include "fullarm/hil/io_device.hpp"

namespace fullarm::identification::detail {

/// Cosine blend from 0 to 1 over [0, 1] (zero slope at both ends: the hold target starts and
/// stops without a step in velocity).
inline double blend(double s) noexcept {
  if (s <= 0.0) return 0.0;
  if (s >= 1.0) return 1.0;
  return 0.5 - 0.5 * std::cos(std::numbers::pi * s);
}

/// The angles a held joint must stay between.
struct LimitBand {
  double lo = 0.0;
  double hi = 0.0;
  [[nodiscard]] bool contains(double q) const noexcept { return q >= lo && q <= hi; }
};

/// A joint's band on its first move from `start`: its limits less the margin, except that from a
/// start inside the margin (and inside the limits: an arm resting at a stop) it may come no
/// closer to the limit than it started, less half the margin for the readings' noise and the sag
/// onto the stop while the hold takes the load. A start beyond the limits (or not finite) gets the
/// ordinary band, so the run stops at once.
inline LimitBand firstMoveBand(double start, double min, double max, double margin) noexcept {
  LimitBand band{min + margin, max - margin};
  if (start >= min && start <= max) {
    if (start < band.lo) band.lo = start - 0.5 * margin;
    if (start > band.hi) band.hi = start + 0.5 * margin;
  }
  return band;
}

/// Deactivates the device however the run ends.
struct DeactivateOnExit {
  hil::IoDevice& device;
  ~DeactivateOnExit() { device.deactivate(); }
};

/// Reads the device after the caller's pacing (`before_read`, empty: none); a pacing that
/// reports a missed period fails the read without reading.
class PacedReader {
 public:
  PacedReader(hil::IoDevice& device, const std::function<bool()>& before_read)
      : device_(device), before_read_(before_read) {}

  /// Reads into `sample`; false on a missed period or a failed read (failure() says which).
  [[nodiscard]] bool read(hil::JointSample& sample) {
    paced_ = !before_read_ || before_read_();
    return paced_ && device_.read(sample).ok();
  }

  /// Why the last read failed.
  [[nodiscard]] std::string failure() const {
    return paced_ ? std::string("device read failed: ") + device_.status().message
                  : std::string("the read came more than half a control period late (pacing overrun)");
  }

 private:
  hil::IoDevice& device_;
  const std::function<bool()>& before_read_;
  bool paced_ = true;
};

}  // namespace fullarm::identification::detail
