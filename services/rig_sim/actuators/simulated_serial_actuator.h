#pragma once

// A simulated serial tendon actuator: serves the line protocol of
// docs/actuators.md on a file descriptor (a pty's master end) from its own
// thread, with one AxisMotion per axis. Faults and link troubles can be
// injected, and what it received is counted, for the tests and for manual
// use (shapesense-actuator-sim).

#include <atomic>
#include <cstdint>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "libs/actuation/axis_motion.h"
#include "libs/actuation/line_protocol.h"

namespace shapesense {

struct SimulatedSerialActuatorOptions {
  int axes = 4;
  double max_speed_mm_s = 50.0;
  double travel_mm = 50.0;  // targets beyond ±travel_mm are refused (E 4)
  std::string name = "shapesense-sim";
};

class SimulatedSerialActuator {
 public:
  struct Counters {
    int64_t lines = 0;            // complete lines received
    int64_t checksum_errors = 0;  // lines refused with E 1
    int64_t targets = 0;          // T commands taken
    int64_t refused_targets = 0;  // T commands refused (range, axis, fault)
    int64_t stops = 0;            // X commands
    int64_t watchdog_stops = 0;   // holds because no valid line came in time
  };

  // Serves on `fd` once started; the descriptor stays the caller's.
  SimulatedSerialActuator(int fd, SimulatedSerialActuatorOptions options);
  ~SimulatedSerialActuator();
  SimulatedSerialActuator(const SimulatedSerialActuator&) = delete;
  SimulatedSerialActuator& operator=(const SimulatedSerialActuator&) = delete;

  void Start();
  // Ends the serving thread (bounded: it polls every few ms).
  void Stop();

  // The protocol without the descriptor: the encoded reply to one received
  // line (without '\n') at steady time `now_us`, or "" for none.
  std::string HandleLine(std::string_view line, int64_t now_us);

  // Every axis holds; T is refused with E 5 until R (which clears it).
  void InjectFault(int code, const std::string& reason);
  // The next `count` replies carry a wrong checksum.
  void CorruptReplies(int count);
  // The next `count` received lines arrive with one byte damaged (line noise).
  void CorruptRequests(int count);
  // Muted: lines are read and acted on, but nothing is answered.
  void SetMuted(bool muted);

  std::vector<double> positions() const;
  std::vector<double> targets() const;
  Counters counters() const;

 private:
  void Serve();
  void ServeOnce(serial_protocol::LineAssembler& assembler);
  void WriteReply(const std::string& reply);
  void AdvanceLocked(int64_t now_us);
  void MoveLocked(int64_t until_us);
  std::string ReplyLocked(const std::vector<std::string>& words);
  std::string TargetLocked(const std::vector<std::string>& words);
  std::string WatchdogLocked(const std::vector<std::string>& words);
  std::string PositionsLocked() const;

  const int fd_;
  const SimulatedSerialActuatorOptions options_;
  mutable std::mutex mutex_;
  std::vector<AxisMotion> axes_;
  int64_t last_advance_us_ = 0;
  int64_t last_valid_line_us_ = 0;
  int64_t watchdog_us_ = 0;  // 0: off
  bool watchdog_tripped_ = false;
  int fault_code_ = 0;  // 0: no fault
  std::string fault_reason_;
  int corrupt_replies_ = 0;
  int corrupt_requests_ = 0;
  bool muted_ = false;
  Counters counters_;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace shapesense
