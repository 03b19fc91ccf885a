#pragma once
/// @file
/// What the I/O device of a HilSession serves, as an I/O node says it (IoNodeInfo, lcm_io.hpp): the
/// plant node `fullarm plant serve` describes the simulated DTS it serves with it.

#include "fullarm/hil/lcm_io.hpp"
#include "fullarm/hil/run.hpp"

namespace fullarm::hil {

/// What the device of `session` serves: its joints' names in device order, its period, whether
/// it is simulated (sim, fakedaq: true), whether a scripted user is strapped in, and (simulated
/// back-ends) the plant file's name and the SHA-256 of its contents, as a run log's header
/// records it ("dts_plant.yaml sha256 <hex>").
/// @throws std::runtime_error naming the plant file if it cannot be read
[[nodiscard]] IoNodeInfo describeSessionDevice(HilSession& session);

}  // namespace fullarm::hil
