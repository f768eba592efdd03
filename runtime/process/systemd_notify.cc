#include "runtime/process/systemd_notify.h"

#include <systemd/sd-daemon.h>

#include <sys/socket.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <stdexcept>

namespace shapesense {
namespace {

std::chrono::microseconds WatchdogTimeoutFromEnvironment() {
  uint64_t usec = 0;
  // 0: do not unset the environment (children and tests read it too).
  if (sd_watchdog_enabled(0, &usec) <= 0) return std::chrono::microseconds(0);
  return std::chrono::microseconds(static_cast<int64_t>(usec));
}

}  // namespace

SystemdNotifier::SystemdNotifier()
    : enabled_(std::getenv("NOTIFY_SOCKET") != nullptr),
      watchdog_timeout_(enabled_ ? WatchdogTimeoutFromEnvironment()
                                 : std::chrono::microseconds(0)) {}

void SystemdNotifier::Ready(const std::string& status) { Send("READY=1\nSTATUS=" + status); }

void SystemdNotifier::Watchdog() {
  if (watchdog_timeout_.count() <= 0) return;
  const auto now = std::chrono::steady_clock::now();
  if (now < next_watchdog_ || (healthy_ && !healthy_())) return;
  next_watchdog_ = now + watchdog_timeout_ / 2;
  Send("WATCHDOG=1");
}

void SystemdNotifier::Status(const std::string& status) { Send("STATUS=" + status); }

void SystemdNotifier::Stopping() {
  if (stopping_sent_) return;
  stopping_sent_ = true;
  Send("STOPPING=1");
}

void SystemdNotifier::Send(const std::string& state) const {
  if (!enabled_) return;
  // A supervisor that went away must not stop the service: the result is
  // only whether systemd heard, and there is nothing better to do if not.
  sd_notify(0, state.c_str());
}

int TakeListeningSocket() {
  const int count = sd_listen_fds(1);
  if (count < 0) throw std::runtime_error("LISTEN_FDS: " + std::string(strerror(-count)));
  if (count == 0) return -1;
  if (count > 1) {
    throw std::runtime_error("LISTEN_FDS: " + std::to_string(count) +
                             " sockets passed, expected one (the HTTP port)");
  }
  if (sd_is_socket(SD_LISTEN_FDS_START, AF_UNSPEC, SOCK_STREAM, 1) <= 0) {
    throw std::runtime_error("LISTEN_FDS: the socket passed is not a listening TCP socket");
  }
  return SD_LISTEN_FDS_START;
}

}  // namespace shapesense
