#pragma once

// The live demo's programs while they run: each started with its output
// (stdout and stderr) kept in <logs>/<name>.log, waited for until it is up,
// watched for an early end, and stopped in order.
#include <atomic>
#include <chrono>
#include <filesystem>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "clients/tools/demo/demo_plan.h"
#include "runtime/process/child_process.h"

namespace shapesense {

// A program of the demo failed: it could not start, ended early, or never
// came up. The message names it and shows its last output.
class DemoFailure : public std::runtime_error {
 public:
  DemoFailure(std::string program, const std::string& message)
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

// The programs of `plan` that are missing or not executable, each with what
// to do about it; empty when all are there.
std::vector<std::string> MissingPrograms(const DemoPlan& plan);

class DemoProcesses {
 public:
  // `pump(ms)`: lets the caller's LCM bus work for up to `ms` while waiting;
  // `status_seen(service)`: whether that service's status has arrived.
  struct Hooks {
    std::function<void(int ms)> pump;
    std::function<bool(const std::string& service)> status_seen;
  };

  DemoProcesses(std::filesystem::path logs_dir, const std::atomic<bool>& stop, Hooks hooks);
  ~DemoProcesses();  // stops whatever still runs
  DemoProcesses(const DemoProcesses&) = delete;
  DemoProcesses& operator=(const DemoProcesses&) = delete;

  // Starts `process` and waits until it is up, or for a one-off job until it
  // has ended well. False when `stop` was set meanwhile. Throws DemoFailure.
  bool Start(const DemoProcess& process, std::chrono::seconds timeout);
  // Starts `process` without waiting; then WaitUntilUp(name) (several
  // programs can start side by side).
  void Launch(const DemoProcess& process);
  bool WaitUntilUp(const std::string& name, std::chrono::seconds timeout);
  // Reads every program's output (a program whose pipe fills up blocks).
  void ReadOutput();
  // Throws DemoFailure when a program has ended that should still run.
  void CheckRunning();
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
    DemoProcess process;
    std::unique_ptr<ChildProcess> child;
  };

  Running& Find(const std::string& name);
  bool IsUp(Running& running);
  DemoFailure Failure(const Running& running, const std::string& what) const;

  std::filesystem::path logs_dir_;
  const std::atomic<bool>& stop_;
  Hooks hooks_;
  std::vector<Running> running_;
  std::vector<ProgramEnd> ends_;
};

}  // namespace shapesense
