#pragma once
// What the experiment and the static holds share when they drive an IoDevice: the device
// deactivated however the run ends, and reads preceded by the caller's pacing.

#include <functional>
#include <string>

#include "fullarm/hil/io_device.hpp"

namespace fullarm::identification::detail {

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
