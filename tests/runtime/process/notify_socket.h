#pragma once

// The supervisor's end of sd_notify for tests: an AF_UNIX datagram socket
// bound in a fresh temporary folder, named by NOTIFY_SOCKET while it lives,
// with the states that arrive read as lines ("READY=1", "WATCHDOG=1", ...).
#include <chrono>
#include <filesystem>
#include <string>
#include <vector>

namespace shapesense::testing {

class NotifySocket {
 public:
  // Binds the socket and sets NOTIFY_SOCKET (and WATCHDOG_USEC when
  // `watchdog_usec` > 0; WATCHDOG_PID is left unset, so any process that
  // inherits the environment may ping).
  explicit NotifySocket(long watchdog_usec = 0);
  // Unsets NOTIFY_SOCKET, WATCHDOG_USEC and WATCHDOG_PID; removes the folder.
  ~NotifySocket();
  NotifySocket(const NotifySocket&) = delete;
  NotifySocket& operator=(const NotifySocket&) = delete;

  // Reads messages until one has the line `state`; false when none does
  // within `timeout`. Every line read is kept in lines().
  bool WaitFor(const std::string& state, std::chrono::milliseconds timeout);
  // How many messages with the line `state` arrive within `window` (reads
  // for the whole window).
  int Count(const std::string& state, std::chrono::milliseconds window);
  // Reads what has arrived, without waiting.
  void Drain();
  const std::vector<std::string>& lines() const { return lines_; }
  // Everything read so far, one state a line, for failure messages.
  std::string Transcript() const;

 private:
  // One message's lines, or nothing when none comes within `timeout`.
  std::vector<std::string> Receive(std::chrono::milliseconds timeout);

  std::filesystem::path folder_;
  int fd_ = -1;
  std::vector<std::string> lines_;
};

}  // namespace shapesense::testing
