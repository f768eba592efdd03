#pragma once

// An SDO client for expedited transfers (objects of up to 4 bytes), one at a
// time, each bounded by a timeout. Frames that arrive while it waits and are
// not its answer (heartbeats, EMCY, PDOs) go to a handler, so nothing the
// master must see is lost during a configuration.

#include <chrono>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>

#include "libs/actuation/can_bus.h"

namespace shapesense {

// A transfer failed: the drive aborted it (abort_code() is the CiA 301 code)
// or did not answer in time (abort_code() 0). The message names the node, the
// direction, the object and the reason, e.g. "node 2: SDO write 6060:00 = 3
// aborted: 0x06090030 (invalid value for parameter)".
class SdoError : public std::runtime_error {
 public:
  SdoError(const std::string& what, uint32_t abort_code)
      : std::runtime_error(what), abort_code_(abort_code) {}
  uint32_t abort_code() const { return abort_code_; }

 private:
  uint32_t abort_code_;
};

class SdoClient {
 public:
  using FrameHandler = std::function<void(const CanFrame&)>;

  SdoClient(CanBus& bus, std::chrono::microseconds timeout, FrameHandler other_frames);

  // Reads an object: its raw value (sign-extend by its type). Throws SdoError;
  // CanBusError when the bus fails.
  uint32_t Upload(int node, uint16_t index, uint8_t subindex);
  // Writes `size` bytes (1, 2 or 4) of `value`. Throws SdoError, CanBusError.
  void Download(int node, uint16_t index, uint8_t subindex, uint32_t value, uint8_t size);

  int64_t timeouts() const { return timeouts_; }

 private:
  // Sends `request` and returns the server's answer about the same object.
  struct Answer;
  Answer Transfer(int node, const CanFrame& request, uint16_t index, uint8_t subindex,
                  const std::string& what);

  CanBus& bus_;
  std::chrono::microseconds timeout_;
  FrameHandler other_frames_;
  int64_t timeouts_ = 0;
};

}  // namespace shapesense
