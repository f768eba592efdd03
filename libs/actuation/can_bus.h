#pragma once

// The CAN bus as the CANopen master and the simulated drives see it: send and
// receive classic frames (11-bit identifiers, up to 8 bytes) with timeouts.
// SocketCAN is the real one (socketcan_bus.h); an in-memory bus stands in for
// it in tests, since this build machine's kernel has no CAN.

#include <array>
#include <chrono>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace shapesense {

struct CanFrame {
  uint32_t id = 0;   // 11-bit identifier (COB-ID)
  uint8_t size = 0;  // data bytes, 0-8
  std::array<uint8_t, 8> data{};

  bool operator==(const CanFrame&) const = default;
};

// "0x602 [8] 40 41 60 00 00 00 00 00", for messages and logs.
std::string DescribeFrame(const CanFrame& frame);

// The bus cannot be used: no CAN in the kernel, no such interface, the
// interface is down, bus-off. The message names the interface and the cause.
class CanBusError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// One node's connection to a bus: it receives what the other nodes send.
// Send and Receive may be called from different threads.
class CanBus {
 public:
  virtual ~CanBus() = default;

  // "can0", "memory:master", ...
  virtual std::string name() const = 0;
  // Queues one frame; throws CanBusError when it cannot go out.
  virtual void Send(const CanFrame& frame) = 0;
  // The next frame another node sent, waiting up to `timeout` (0: only what
  // is there); nullopt when none came. Throws CanBusError when the link is down.
  virtual std::optional<CanFrame> Receive(std::chrono::microseconds timeout) = 0;
};

}  // namespace shapesense
