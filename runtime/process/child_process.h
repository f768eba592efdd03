#pragma once

// A child process of a multi-process run (tests, bench, demo): started with its stdout on a
// pipe, waited for by the lines it prints, and always ended (SIGTERM, then
// SIGKILL) when the handle goes away.

#include <sys/types.h>

#include <chrono>
#include <string>
#include <vector>

namespace shapesense {

class ChildProcess {
 public:
  // Starts `argv[0]` with the arguments; stderr stays the test's.
  explicit ChildProcess(const std::vector<std::string>& argv);
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Reads the child's output until a line contains `text`; false when it does
  // not within `timeout` (or the child exits). Every line read is kept.
  bool WaitForLine(const std::string& text, std::chrono::milliseconds timeout);
  const std::string& output() const { return output_; }

  void Signal(int signal) const;
  // SIGTERM, then SIGKILL after `grace`; returns the exit status (waitpid's),
  // or -1 when it had to be killed.
  int Stop(std::chrono::milliseconds grace = std::chrono::milliseconds(5000));

 private:
  pid_t pid_ = -1;
  int out_fd_ = -1;
  std::string output_;
  size_t scanned_ = 0;
};

}  // namespace shapesense
