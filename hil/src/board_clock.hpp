#pragma once
// What passes between two reads of a simulated Comedi board (private to the hil module): the
// fake DAQ's rig advances the simulated DTS by one period. A real board has none.

#include "fullarm/core/rt_status.hpp"

namespace fullarm::hil {

struct BoardClock {
  core::RtStatus (*before_read)(void* context) noexcept = nullptr;
  void* context = nullptr;
};

}  // namespace fullarm::hil
