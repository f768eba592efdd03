#pragma once

// A group of programs run together on one machine (the live demo, the
// closed-loop experiment, the end-to-end tests): each started with its
// output (stdout and stderr) kept in <logs>/<name>.log, waited for until it
// is up, watched for an early end, and stopped in order. A rig's hosts run
// their programs under systemd instead (deploy/).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "runtime/process/child_process.h"

namespace shapesense {

// One program of a group.
struct ProgramSpec {
  std::string name;  // short, for messages and its log file: "rig-sim", "capture", ...
  std::vector<std::string> argv;
  // It is up once its output has a line containing `ready_line`, or once its
  // service status has arrived on LCM (`ready_status`, the service's name);
  // neither: once started.
  std::string ready_line;
  std::string ready_status;
  // It runs to its end (a one-off job) instead of until the group stops it.
  bool runs_to_end = false;
  // Its nice value (0: the launcher's). The demo raises the virtual rig's
  // cameras and the capture service's triggers, which stand for hardware and
  // a real-time process, where allowed (as root), so that another load on
  // the machine delays the measuring, not the exposures.
  int nice = 0;
  // Where it runs (ChildOptions): a network namespace (-1: the launcher's),
  // a host name of its own (empty: the launcher's), variables set in its
  // environment. VirtualHosts::PlaceOn fills them for a virtual host.
  int network_namespace = -1;
  std::string host_name = {};
  std::vector<std::pair<std::string, std::string>> environment = {};
  // Started again, at once, whenever it ends while the group runs: a stand-in
  // for systemd's Restart=on-failure in the tests and the demo's faults. Its
  // output goes on in the same log. An end after 5 restarts is a failure.
  bool restart = false;
  // A listening socket it gets as systemd would pass it (ChildOptions); -1: none.
  int listen_socket = -1;
};

// A program of the group failed: it could not start, ended early, or never
// came up. The message names it and shows its last output.
class ProgramFailure : public std::runtime_error {
 public:
  ProgramFailure(std::string program, const std::string& message)
      : std::runtime_error(message), program_(std::move(program)) {}
  const std::string& program() const { return program_; }

 private:
  std::string program_;
};

// How one program ended.
struct ProgramEnd {
  std::string name;
  std::string how;  // "exited with status 0", ...
  bool clean = false;
  std::vector<std::string> argv;  // how it was run (empty: it was not)
};

// `name` on $PATH; empty when it is not there.
std::filesystem::path FindOnPath(const std::string& name);

class ProcessGroup {
 public:
  // `pump(ms)`: lets the caller's LCM bus work for up to `ms` while waiting;
  // `status_seen(service)`: whether that service's status has arrived.
  struct Hooks {
    std::function<void(int ms)> pump;
    std::function<bool(const std::string& service)> status_seen;
  };

  ProcessGroup(std::filesystem::path logs_dir, const std::atomic<bool>& stop, Hooks hooks);
  ~ProcessGroup();  // stops whatever still runs
  ProcessGroup(const ProcessGroup&) = delete;
  ProcessGroup& operator=(const ProcessGroup&) = delete;

  // Starts `process` and waits until it is up, or for a one-off job until it
  // has ended well. False when `stop` was set meanwhile. Throws ProgramFailure.
  bool Start(const ProgramSpec& process, std::chrono::seconds timeout);
  // Starts `process` without waiting; then WaitUntilUp(name) (several
  // programs can start side by side).
  void Launch(const ProgramSpec& process);
  bool WaitUntilUp(const std::string& name, std::chrono::seconds timeout);
  // Reads every program's output (a program whose pipe fills up blocks).
  void ReadOutput();
  // Throws ProgramFailure when a program has ended that should still run (a
  // one-off job may end: Stop() then records how);
  // restarts one that ended and is to be restarted (ProgramSpec::restart).
  void CheckRunning();
  // How often the program was restarted, and when last (µs, HostUtime; 0: never).
  int restarts(const std::string& name) const;
  int64_t last_restart_utime(const std::string& name) const;
  // Stops one program (SIGTERM, SIGKILL after a grace period); stopping
  // one that already ended only records how it ended.
  ProgramEnd Stop(const std::string& name);
  // Sends `signal` to a running program (faults in tests: SIGSTOP freezes it).
  void Signal(const std::string& name, int signal);
  // Whether the program is started and has not ended.
  bool IsRunning(const std::string& name);
  // Stops the rest, the last started first.
  void StopAll();
  // How every program that has ended so far ended, in that order.
  const std::vector<ProgramEnd>& ends() const { return ends_; }

 private:
  struct Running {
    ProgramSpec process;
    std::unique_ptr<ChildProcess> child;
    int restarts = 0;
    int64_t last_restart_utime = 0;
  };

  Running& Find(const std::string& name);
  const Running* FindOrNull(const std::string& name) const;
  std::unique_ptr<ChildProcess> StartChild(const ProgramSpec& process, bool keep_log) const;
  void Restart(Running& running, int status);
  bool IsUp(Running& running);
  ProgramFailure Failure(const Running& running, const std::string& what) const;

  std::filesystem::path logs_dir_;
  const std::atomic<bool>& stop_;
  Hooks hooks_;
  std::vector<Running> running_;
  std::vector<ProgramEnd> ends_;
};

}  // namespace shapesense
