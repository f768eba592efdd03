#include "services/controller/actuators/serial_driver.h"

#include <cmath>
#include <stdexcept>
#include <thread>

#include "libs/actuation/line_protocol.h"
#include "runtime/devices/device_clock.h"

namespace shapesense {
namespace {

using serial_protocol::DeviceError;

// The device answered "E <code> <text>" (or something that makes no sense).
class DeviceRefusal : public ActuatorError {
 public:
  DeviceRefusal(int code, const std::string& what) : ActuatorError(what), code_(code) {}
  int code() const { return code_; }

 private:
  int code_;
};

constexpr int64_t kConnectPauseUs = 50'000;

// "T 2" answers "T 2 12.5000" but not "T 21 3.0000".
bool Answers(const std::string& body, const std::string& answer) {
  return body == answer || body.starts_with(answer + " ");
}

// The words after the first `skip`, joined by spaces.
std::string JoinFrom(const std::vector<std::string>& words, size_t skip) {
  std::string text;
  for (size_t i = skip; i < words.size(); ++i) text += (text.empty() ? "" : " ") + words[i];
  return text;
}

DeviceRefusal RefusalOf(const std::vector<std::string>& words, const std::string& request) {
  const int code = words.size() > 1 ? serial_protocol::ParseInteger(words[1]).value_or(0) : 0;
  return DeviceRefusal(code, "the actuator refused '" + request + "': E " + std::to_string(code) +
                                 " " + JoinFrom(words, 2));
}

}  // namespace

SerialActuatorDriver::SerialActuatorDriver(SerialActuatorOptions options, int axes)
    : options_(std::move(options)), axes_(axes) {
  if (const std::string error = options_.Validate(); !error.empty()) {
    throw std::invalid_argument("serial actuator: " + error);
  }
}

SerialActuatorDriver::~SerialActuatorDriver() { Disconnect(); }

template <class Talk>
auto SerialActuatorDriver::Guarded(Talk&& talk) {
  try {
    return talk();
  } catch (const SerialLinkLost& e) {
    LoseLink(std::string("serial ") + e.what());
  } catch (const DeviceRefusal& e) {
    EnterFault(static_cast<uint32_t>(e.code()), description() + ": " + e.what());
  }
  throw ActuatorError(status_.reason);
}

std::vector<std::string> SerialActuatorDriver::TryExchange(const std::string& body,
                                                           const std::string& answer) {
  port_->DiscardInput();
  const int64_t sent_us = SteadyMicros();
  const int64_t deadline_us = sent_us + SecondsToMicros(options_.reply_timeout_s);
  port_->Write(serial_protocol::EncodeLine(body), deadline_us);
  while (const std::optional<std::string> line = port_->ReadLine(deadline_us)) {
    const serial_protocol::DecodedLine decoded = serial_protocol::DecodeLine(*line);
    std::vector<std::string> words = serial_protocol::SplitWords(decoded.body);
    if (!decoded.ok() || words.empty()) {
      ++health_.corrupt_replies;
      return {};
    }
    if (words[0] == "E") {
      if (words.size() > 1 &&
          words[1] == std::to_string(static_cast<int>(DeviceError::kChecksum))) {
        ++health_.rejected_requests;  // our line arrived damaged: send it again
        return {};
      }
      throw RefusalOf(words, body);
    }
    if (!Answers(decoded.body, answer)) continue;  // a late answer to an earlier try
    health_.round_trip_us = SteadyMicros() - sent_us;
    health_.last_contact_utime = EpochMicros();
    return words;
  }
  ++health_.timeouts;
  return {};
}

std::vector<std::string> SerialActuatorDriver::Exchange(const std::string& body,
                                                        const std::string& answer) {
  for (int attempt = 0; attempt <= options_.retries; ++attempt) {
    if (attempt > 0) ++health_.retries;
    std::vector<std::string> words = TryExchange(body, answer);
    if (!words.empty()) return words;
  }
  throw SerialLinkLost(options_.device + ": no valid reply to '" + body + "' in " +
                       std::to_string(options_.retries + 1) + " tries of " +
                       std::to_string(static_cast<int>(options_.reply_timeout_s * 1000)) +
                       " ms (link lost?)");
}

std::vector<std::string> SerialActuatorDriver::OpenAndIdentify() {
  const int64_t deadline_us = SteadyMicros() + SecondsToMicros(options_.connect_timeout_s);
  for (;;) {
    try {
      port_ = std::make_unique<SerialPort>(options_.device, options_.baud);
      return Exchange("I?", "I");
    } catch (const ActuatorError& e) {
      port_.reset();
      // The port may be re-enumerating (a USB adapter plugged back): try until the deadline.
      if (SteadyMicros() + kConnectPauseUs > deadline_us) {
        throw ActuatorError(description() + ": cannot connect: " + e.what());
      }
    }
    std::this_thread::sleep_for(std::chrono::microseconds(kConnectPauseUs));
  }
}

void SerialActuatorDriver::RequireAxes(const std::vector<std::string>& identity) const {
  const std::optional<int> device_axes =
      identity.size() > 1 ? serial_protocol::ParseInteger(identity[1]) : std::nullopt;
  if (device_axes && *device_axes >= axes_) return;
  throw ActuatorError(description() + ": the actuator has " +
                      (identity.size() > 1 ? identity[1] : "?") +
                      " axes, the configuration needs " + std::to_string(axes_));
}

void SerialActuatorDriver::ClearDeviceFault() {
  std::vector<std::string> state = Exchange("S?", "S");
  if (state.size() < 2 || state[1] != "FAULT") return;
  Exchange("R", "R");
  state = Exchange("S?", "S");
  if (state.size() >= 2 && state[1] == "FAULT") {
    const int code = state.size() > 2 ? serial_protocol::ParseInteger(state[2]).value_or(0) : 0;
    throw DeviceRefusal(
        code, "fault " + std::to_string(code) + " persists after a reset: " + JoinFrom(state, 3));
  }
}

void SerialActuatorDriver::Connect() {
  port_.reset();
  status_ = {ActuatorState::kDisconnected, description() + ": connecting", 0};
  try {
    RequireAxes(OpenAndIdentify());
  } catch (const ActuatorError& e) {
    port_.reset();
    status_.reason = e.what();
    throw;
  }
  Guarded([&] {
    ClearDeviceFault();
    const int watchdog_ms = static_cast<int>(std::lround(options_.device_watchdog_s * 1000));
    Exchange("W " + std::to_string(watchdog_ms), "W");
    Exchange("X", "X");  // hold where it stands until the first target
  });
  status_ = {ActuatorState::kOk, "", 0};
  ++health_.connects;
}

void SerialActuatorDriver::Disconnect() {
  Stop();
  port_.reset();
  status_ = {ActuatorState::kDisconnected, description() + ": disconnected by the controller", 0};
}

void SerialActuatorDriver::RequireState(bool allow_fault, const char* action) const {
  const bool allowed = status_.state == ActuatorState::kOk ||
                       (allow_fault && status_.state == ActuatorState::kFault);
  if (allowed && port_) return;
  throw ActuatorError(description() + ": " + action + " refused while " +
                      ActuatorStateName(status_.state) + " (" + status_.reason +
                      "); Connect() first");
}

void SerialActuatorDriver::CommandTargets(std::span<const double> target_mm) {
  RequireState(/*allow_fault=*/false, "target");
  if (static_cast<int>(target_mm.size()) != axes_) {
    throw ActuatorError(description() + ": expected " + std::to_string(axes_) + " targets, got " +
                        std::to_string(target_mm.size()));
  }
  for (const double mm : target_mm) {
    if (!std::isfinite(mm)) throw ActuatorError(description() + ": a target is not a number");
  }
  Guarded([&] {
    for (int axis = 0; axis < axes_; ++axis) {
      const std::string name = "T " + std::to_string(axis);
      Exchange(name + " " + serial_protocol::FormatMm(target_mm[static_cast<size_t>(axis)]), name);
    }
  });
}

ActuatorPositions SerialActuatorDriver::ReadPositions() {
  RequireState(/*allow_fault=*/true, "position read");
  return Guarded([&] {
    const int64_t before = EpochMicros();
    const std::vector<std::string> words = Exchange("P?", "P");
    ActuatorPositions positions;
    positions.utime = (before + EpochMicros()) / 2;
    for (int axis = 0; axis < axes_; ++axis) {
      const size_t word = static_cast<size_t>(axis) + 1;
      const std::optional<double> mm =
          word < words.size() ? serial_protocol::ParseNumber(words[word]) : std::nullopt;
      if (!mm) {
        throw DeviceRefusal(static_cast<int>(DeviceError::kSyntax),
                            "malformed position reply '" + JoinFrom(words, 0) + "'");
      }
      positions.mm.push_back(*mm);
    }
    return positions;
  });
}

ActuatorStatus SerialActuatorDriver::Status() {
  if (status_.state != ActuatorState::kOk || !port_) return status_;
  try {
    Guarded([&] {
      const std::vector<std::string> state = Exchange("S?", "S");
      if (state.size() >= 3 && state[1] == "FAULT") {
        throw DeviceRefusal(serial_protocol::ParseInteger(state[2]).value_or(0),
                            "actuator fault " + state[2] + ": " + JoinFrom(state, 3));
      }
    });
  } catch (const ActuatorError&) {
    // The state says what happened.
  }
  return status_;
}

void SerialActuatorDriver::Stop() {
  if (!port_ || status_.state == ActuatorState::kDisconnected) return;
  try {
    Guarded([&] { Exchange("X", "X"); });
  } catch (const ActuatorError&) {
    // Best effort: the state says why the stop did not get through.
  }
}

ActuatorHealth SerialActuatorDriver::Health() {
  health_.link_alive = port_ != nullptr && status_.state != ActuatorState::kDisconnected;
  return health_;
}

void SerialActuatorDriver::LoseLink(const std::string& reason) {
  // Nothing can reach the actuator any more; its own watchdog holds it.
  port_.reset();
  status_ = {ActuatorState::kDisconnected, reason, 0};
}

void SerialActuatorDriver::EnterFault(uint32_t code, const std::string& reason) {
  status_ = {ActuatorState::kFault, reason, code};
  try {
    Exchange("X", "X");
  } catch (const SerialLinkLost& e) {
    LoseLink(std::string("serial ") + e.what());
  } catch (const ActuatorError&) {
    // The fault stays the state; the device refused even the stop.
  }
}

}  // namespace shapesense
