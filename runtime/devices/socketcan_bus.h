#pragma once

// The CanBus on Linux SocketCAN: a raw CAN socket (PF_CAN, SOCK_RAW,
// CAN_RAW) bound to one interface (can0, or vcan0 for a virtual bus).

#include <memory>
#include <string>

#include "libs/actuation/can_bus.h"

namespace shapesense {

// Opens `interface`. Throws CanBusError with the reason and what to do: the
// kernel has no CAN support (as on this build machine), no such interface,
// the interface is down.
std::unique_ptr<CanBus> OpenSocketCanBus(const std::string& interface);

}  // namespace shapesense
