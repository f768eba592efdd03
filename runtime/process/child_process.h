#pragma once

// A child process of a multi-process run (tests, bench, demo): started with its stdout on a
// pipe, waited for by the lines it prints, and always ended (SIGTERM, then
// SIGKILL) when the handle goes away.

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace shapesense {

struct ChildOptions {
  // Also read the child's stderr (merged with its stdout); else it stays the parent's.
  bool capture_stderr = false;
  // Everything read from the child is appended here too (empty: nowhere).
  std::filesystem::path log_file;
  // A process group of its own: a terminal's Ctrl-C then reaches only the
  // parent, which can stop its children in order.
  bool own_process_group = false;
  // SIGTERM the child when the thread that started it dies, so that a parent
  // that crashes or is killed leaves no orphan running.
  bool end_with_parent = false;
  // The child's nice value when not 0. Raising priority (< 0) needs
  // privileges; refused, the child runs at normal priority and its output
  // starts with a line that says so.
  int nice = 0;
  // A network namespace (an open fd, e.g. VirtualHosts::NamespaceFd) the
  // child enters before exec; -1: the parent's.
  int network_namespace = -1;
  // When set, the child gets a UTS namespace of its own with this host name,
  // so that gethostname() in the program names its (virtual) host.
  std::string host_name = {};
  // Variables set in the child's environment (replacing the parent's).
  std::vector<std::pair<std::string, std::string>> environment = {};
  // A listening socket handed to the child as systemd hands one to a
  // socket-activated service: as fd 3, with LISTEN_FDS=1 and LISTEN_PID set
  // to the child's pid (sd_listen_fds). -1: none.
  int listen_socket = -1;
};

class ChildProcess {
 public:
  // Starts `argv[0]` (a path) with the arguments. Throws std::runtime_error
  // naming the program when it cannot be started (missing, not executable,
  // its network namespace or host name refused) and the step that failed.
  explicit ChildProcess(const std::vector<std::string>& argv, const ChildOptions& options = {});
  ~ChildProcess();
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;

  // Reads the child's output until a line contains `text`; false when it does
  // not within `timeout` (or the child exits). Every line read is kept.
  bool WaitForLine(const std::string& text, std::chrono::milliseconds timeout);
  // Reads what the child has written so far, without waiting (a child whose
  // pipe is never read blocks once the pipe is full).
  void ReadAvailable();
  const std::string& output() const { return output_; }
  // The last `lines` lines of what was read.
  std::string Tail(int lines) const;

  // The exit status (waitpid's) once the child has ended, without waiting;
  // nullopt while it runs.
  std::optional<int> ExitStatus();
  pid_t pid() const { return pid_; }

  void Signal(int signal) const;
  // `signal` (SIGTERM), then SIGKILL after `grace`, reading the output
  // meanwhile; returns the exit status (waitpid's), or -1 when it had to be
  // killed. A child that had already ended gives its status.
  int Stop(std::chrono::milliseconds grace = std::chrono::milliseconds(5000));
  int Stop(int signal, std::chrono::milliseconds grace);

 private:
  bool ReadOnce(int timeout_ms);

  pid_t pid_ = -1;
  int out_fd_ = -1;
  std::optional<int> status_;
  std::string output_;
  size_t scanned_ = 0;
  std::ofstream log_;
};

// A waitpid status in words: "exited with status 2", "killed by signal 9 (Killed)".
std::string DescribeExitStatus(int status);

}  // namespace shapesense
