#include <stdexcept>

#include "fullarm/hil/run.hpp"

namespace fullarm::hil {

RunResult HilSession::runRealtime(const RunHooks& /*hooks*/) {
  throw std::runtime_error("the real-time clock is not available in this build");
}

}  // namespace fullarm::hil
