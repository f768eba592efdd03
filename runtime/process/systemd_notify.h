#pragma once

// What a service tells systemd when it runs as a Type=notify unit: ready,
// alive (the watchdog), its status in words, stopping. Over libsystemd's
// sd_notify; does nothing when NOTIFY_SOCKET is unset (not under systemd,
// or in a test), so the services call it unconditionally.
#include <chrono>
#include <functional>
#include <string>

namespace shapesense {

class SystemdNotifier {
 public:
  // Reads NOTIFY_SOCKET and the watchdog period (WATCHDOG_USEC, for this
  // process when WATCHDOG_PID is set) once. The environment is left as it
  // is, so that a child started later sees what this process saw.
  SystemdNotifier();

  // True when a supervisor listens (NOTIFY_SOCKET is set).
  bool enabled() const { return enabled_; }
  // The supervisor's watchdog timeout; zero when it asked for none.
  std::chrono::microseconds watchdog_timeout() const { return watchdog_timeout_; }

  // READY=1 with a status line: call once the service can do its work.
  void Ready(const std::string& status);
  // WATCHDOG=1 at most once per half the watchdog timeout (systemd's
  // advice), so a loop can call it every iteration. Call it from the loop
  // that does the work: when that loop hangs, the pings stop and systemd
  // restarts the service.
  void Watchdog();
  // A check Watchdog asks before each ping: a service whose work runs on
  // another thread than its loop (a worker) says there whether that thread
  // is stuck, so that a hung worker also stops the pings.
  void SetHealthCheck(std::function<bool()> healthy) { healthy_ = std::move(healthy); }
  // STATUS=text, shown by `systemctl status`.
  void Status(const std::string& status);
  // STOPPING=1, once: the service is going down on purpose.
  void Stopping();

 private:
  void Send(const std::string& state) const;

  bool enabled_ = false;
  std::chrono::microseconds watchdog_timeout_{0};
  std::chrono::steady_clock::time_point next_watchdog_{};
  bool stopping_sent_ = false;
  std::function<bool()> healthy_;
};

// The listening socket that systemd (a .socket unit) or a parent using its
// protocol (LISTEN_FDS, LISTEN_PID: the demo hands the monitor a socket
// made in the host's network) passed to this process; -1 when none. Throws
// std::runtime_error when several were passed or it is not a listening
// TCP socket. Unsets the variables, so that children do not see them.
int TakeListeningSocket();

}  // namespace shapesense
