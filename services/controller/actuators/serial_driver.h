#pragma once

// The serial actuator driver: the line protocol of docs/actuators.md over a
// tty (termios raw 8N1). Every exchange is one request and one reply, each
// with a CRC-8; a timeout, a corrupt reply or a device checksum error sends
// the request again (every command is idempotent), up to `retries` times; a
// hang-up or no valid reply after the retries is a lost link: the driver
// closes the port, reports it, and sends nothing more until Connect().

#include <memory>
#include <span>
#include <string>
#include <vector>

#include "runtime/devices/serial_port.h"
#include "services/controller/actuators/actuator_driver.h"
#include "services/controller/actuators/actuator_options.h"

namespace shapesense {

class SerialActuatorDriver : public ActuatorDriver {
 public:
  SerialActuatorDriver(SerialActuatorOptions options, int axes);
  ~SerialActuatorDriver() override;

  int axis_count() const override { return axes_; }
  std::string description() const override { return "serial " + options_.device; }
  void Connect() override;
  void Disconnect() override;
  void CommandTargets(std::span<const double> target_mm) override;
  ActuatorPositions ReadPositions() override;
  ActuatorStatus Status() override;
  void Stop() override;
  ActuatorHealth Health() override;

 private:
  // Sends `body` and returns the words of the reply that answers it (its
  // first word is `answer`). Throws SerialLinkLost when the link fails and
  // DeviceRefusal (serial_driver.cc) when the device answers with an error.
  std::vector<std::string> Exchange(const std::string& body, const std::string& answer);
  // One try of Exchange: the reply, or an empty vector to try again.
  std::vector<std::string> TryExchange(const std::string& body, const std::string& answer);
  // Runs `talk`; a lost link or a refusal becomes the state and an ActuatorError.
  template <class Talk>
  auto Guarded(Talk&& talk);
  // Opens the port and asks I? until it answers or connect_timeout_s passes;
  // the identity's words.
  std::vector<std::string> OpenAndIdentify();
  void RequireAxes(const std::vector<std::string>& identity) const;
  void ClearDeviceFault();
  void LoseLink(const std::string& reason);
  void EnterFault(uint32_t code, const std::string& reason);
  void RequireState(bool allow_fault, const char* action) const;

  const SerialActuatorOptions options_;
  const int axes_;
  std::unique_ptr<SerialPort> port_;
  ActuatorStatus status_{ActuatorState::kDisconnected, "not connected yet", 0};
  ActuatorHealth health_;
};

}  // namespace shapesense
