#include "services/controller/actuators/actuator_options.h"

#include "libs/core/error.h"

#include <cmath>
#include <set>
#include <sstream>

namespace shapesense {
namespace {

bool InRange(double value, double low, double high) { return value >= low && value <= high; }

bool IsStandardBaud(int baud) {
  static const std::set<int> kRates = {9600, 19200, 38400, 57600, 115200, 230400, 460800, 921600};
  return kRates.contains(baud);
}

std::string ValidateNodeIds(const std::vector<int>& ids) {
  std::set<int> seen;
  for (size_t i = 0; i < ids.size(); ++i) {
    const std::string key = "node_ids[" + std::to_string(i) + "]";
    if (ids[i] < 1 || ids[i] > 127) return Expected(key, "a node id 1-127", ids[i]);
    if (!seen.insert(ids[i]).second) return Expected(key, "a node id no other drive has", ids[i]);
  }
  if (ids.empty()) return Expected("node_ids", "at least one node id", "none");
  return "";
}

// The largest profile value a drive takes (an UNSIGNED32 in counts/s or counts/s²).
bool FitsUnsigned32(double mm_value, double counts_per_mm) {
  return mm_value * std::abs(counts_per_mm) <= 4294967295.0;
}

std::string ValidateProfile(const CanOpenOptions& o) {
  const std::vector<std::pair<const char*, double>> rates = {
      {"profile_velocity_mm_s", o.profile_velocity_mm_s},
      {"profile_acceleration_mm_s2", o.profile_acceleration_mm_s2},
      {"quick_stop_deceleration_mm_s2", o.quick_stop_deceleration_mm_s2}};
  for (const auto& [key, value] : rates) {
    if (!(value > 0.0) || !std::isfinite(value) || !FitsUnsigned32(value, o.counts_per_mm)) {
      return Expected(key, "a positive number whose counts fit 32 bits", value);
    }
  }
  return "";
}

}  // namespace

std::string SerialActuatorOptions::Validate() const {
  if (device.empty()) return Expected("device", "a serial port path", "''");
  if (!IsStandardBaud(baud)) {
    return Expected("baud", "9600, 19200, 38400, 57600, 115200, 230400, 460800 or 921600", baud);
  }
  if (!InRange(reply_timeout_s, 0.001, 5.0)) {
    return Expected("reply_timeout_s", "0.001-5 s", reply_timeout_s);
  }
  if (retries < 0 || retries > 10) return Expected("retries", "0-10", retries);
  if (!InRange(connect_timeout_s, 0.0, 60.0)) {
    return Expected("connect_timeout_s", "0-60 s", connect_timeout_s);
  }
  if (device_watchdog_s != 0.0 && !InRange(device_watchdog_s, 0.01, 60.0)) {
    return Expected("device_watchdog_s", "0 (off) or 0.01-60 s", device_watchdog_s);
  }
  return "";
}

std::string CanOpenOptions::Validate() const {
  if (interface.empty()) return Expected("interface", "a CAN interface name", "''");
  if (std::string error = ValidateNodeIds(node_ids); !error.empty()) return error;
  if (!std::isfinite(counts_per_mm) || std::abs(counts_per_mm) < 1e-6) {
    return Expected("counts_per_mm", "a non-zero number", counts_per_mm);
  }
  if (std::string error = ValidateProfile(*this); !error.empty()) return error;
  if (!InRange(heartbeat_period_s, 0.01, 10.0)) {
    return Expected("heartbeat_period_s", "0.01-10 s", heartbeat_period_s);
  }
  if (!(heartbeat_timeout_s > heartbeat_period_s) || heartbeat_timeout_s > 60.0) {
    return Expected("heartbeat_timeout_s", "more than heartbeat_period_s and at most 60 s",
                    heartbeat_timeout_s);
  }
  if (!InRange(sdo_timeout_s, 0.001, 5.0))
    return Expected("sdo_timeout_s", "0.001-5 s", sdo_timeout_s);
  if (!InRange(pdo_timeout_s, 0.001, 5.0))
    return Expected("pdo_timeout_s", "0.001-5 s", pdo_timeout_s);
  if (pdo_retries < 0 || pdo_retries > 10) return Expected("pdo_retries", "0-10", pdo_retries);
  if (!InRange(boot_timeout_s, 0.01, 60.0)) {
    return Expected("boot_timeout_s", "0.01-60 s", boot_timeout_s);
  }
  if (!InRange(state_timeout_s, 0.01, 60.0)) {
    return Expected("state_timeout_s", "0.01-60 s", state_timeout_s);
  }
  return "";
}

std::string SimulatedActuatorOptions::Validate() const {
  if (!InRange(time_constant_s, 0.0, 60.0)) {
    return Expected("time_constant_s", "0-60 s", time_constant_s);
  }
  return "";
}

std::string RigActuatorOptions::Validate() const {
  if (!InRange(state_timeout_s, 0.01, 60.0)) {
    return Expected("state_timeout_s", "0.01-60 s", state_timeout_s);
  }
  if (!InRange(connect_timeout_s, 0.01, 60.0)) {
    return Expected("connect_timeout_s", "0.01-60 s", connect_timeout_s);
  }
  return "";
}

std::string ActuatorOptions::Validate() const {
  if (driver != "serial" && driver != "socketcan" && driver != "simulated" && driver != "rig") {
    return Expected("driver", "serial, socketcan, simulated or rig", "'" + driver + "'");
  }
  if (tendons < 1 || tendons > 32) return Expected("tendons", "1-32", tendons);
  if (const std::string error = serial.Validate(); !error.empty()) return "serial." + error;
  if (const std::string error = canopen.Validate(); !error.empty()) return "canopen." + error;
  if (const std::string error = simulated.Validate(); !error.empty()) return "simulated." + error;
  if (const std::string error = rig.Validate(); !error.empty()) return "rig." + error;
  if (driver == "socketcan" && static_cast<int>(canopen.node_ids.size()) != tendons) {
    return Expected("canopen.node_ids", "one node id per tendon (" + std::to_string(tendons) + ")",
                    std::to_string(canopen.node_ids.size()) + " ids");
  }
  return "";
}

}  // namespace shapesense
