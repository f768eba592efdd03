#include "runtime/process/process_group.h"

#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <string_view>

#include "runtime/host_clock.h"

namespace shapesense {
namespace fs = std::filesystem;
namespace {

constexpr int kTailLines = 12;
constexpr auto kStopGrace = std::chrono::milliseconds(10000);
// A program restarted this often is failing, not faulted: as systemd's
// StartLimitBurst, the group gives up on it (deploy/systemd: 5 in 60 s).
constexpr int kMostRestarts = 5;

std::string Indented(const std::string& text) {
  std::string out = "    ";
  for (const char c : text) {
    out += c;
    if (c == '\n') out += "    ";
  }
  return out;
}

}  // namespace

fs::path FindOnPath(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::string_view dirs = path != nullptr ? path : "/usr/local/bin:/usr/bin:/bin";
  while (!dirs.empty()) {
    const size_t colon = dirs.find(':');
    fs::path candidate = fs::path(dirs.substr(0, colon)) / name;
    if (!candidate.parent_path().empty() && access(candidate.c_str(), X_OK) == 0) return candidate;
    dirs = colon == std::string_view::npos ? std::string_view() : dirs.substr(colon + 1);
  }
  return {};
}

ProcessGroup::ProcessGroup(fs::path logs_dir, const std::atomic<bool>& stop, Hooks hooks)
    : logs_dir_(std::move(logs_dir)), stop_(stop), hooks_(std::move(hooks)) {
  fs::create_directories(logs_dir_);
}

ProcessGroup::~ProcessGroup() { StopAll(); }

void ProcessGroup::Launch(const ProgramSpec& process) {
  running_.push_back({process, StartChild(process, false)});
}

std::unique_ptr<ChildProcess> ProcessGroup::StartChild(const ProgramSpec& process,
                                                       bool keep_log) const {
  ChildOptions options;
  options.capture_stderr = true;
  options.log_file = logs_dir_ / (process.name + ".log");
  options.own_process_group = true;  // Ctrl-C reaches the demo, which stops them in order
  options.end_with_parent = true;
  options.nice = process.nice;
  options.network_namespace = process.network_namespace;
  options.host_name = process.host_name;
  options.environment = process.environment;
  options.listen_socket = process.listen_socket;
  if (!keep_log) fs::remove(options.log_file);
  try {
    return std::make_unique<ChildProcess>(process.argv, options);
  } catch (const std::runtime_error& e) {
    throw ProgramFailure(process.name, e.what());
  }
}

bool ProcessGroup::Start(const ProgramSpec& process, std::chrono::seconds timeout) {
  Launch(process);
  return WaitUntilUp(process.name, timeout);
}

ProcessGroup::Running& ProcessGroup::Find(const std::string& name) {
  const auto found = std::find_if(running_.begin(), running_.end(),
                                  [&](const Running& r) { return r.process.name == name; });
  if (found == running_.end()) throw std::logic_error("ProcessGroup: no program " + name);
  return *found;
}

bool ProcessGroup::WaitUntilUp(const std::string& name, std::chrono::seconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (!IsUp(Find(name))) {
    if (stop_) return false;
    if (std::chrono::steady_clock::now() > deadline) {
      throw Failure(Find(name), "did not come up within " + std::to_string(timeout.count()) + " s");
    }
    hooks_.pump(50);
    ReadOutput();
  }
  if (Find(name).process.runs_to_end) Stop(name);  // records how it ended
  return true;
}

// Up: its ready line or status seen; a one-off job: ended with status 0.
bool ProcessGroup::IsUp(Running& running) {
  ChildProcess& child = *running.child;
  const ProgramSpec& process = running.process;
  child.ReadAvailable();
  const std::optional<int> status = child.ExitStatus();
  if (process.runs_to_end && status && *status == 0) return true;
  if (status) {
    child.ReadAvailable();
    throw Failure(running, DescribeExitStatus(*status) + " while starting");
  }
  if (!process.ready_line.empty())
    return child.output().find(process.ready_line) != std::string::npos;
  if (!process.ready_status.empty()) return hooks_.status_seen(process.ready_status);
  return !process.runs_to_end;
}

void ProcessGroup::ReadOutput() {
  for (Running& running : running_) running.child->ReadAvailable();
}

void ProcessGroup::CheckRunning() {
  for (Running& running : running_) {
    running.child->ReadAvailable();
    // A one-off job may end; Stop() records how.
    if (running.process.runs_to_end) continue;
    if (const std::optional<int> status = running.child->ExitStatus()) {
      if (!running.process.restart || running.restarts >= kMostRestarts) {
        throw Failure(running, DescribeExitStatus(*status) + " while the demo ran" +
                                   (running.process.restart
                                        ? ", after " + std::to_string(kMostRestarts) + " restarts"
                                        : ""));
      }
      Restart(running, *status);
    }
  }
}

// Records how it ended and starts it again, as systemd would.
void ProcessGroup::Restart(Running& running, int status) {
  ends_.push_back({running.process.name, DescribeExitStatus(status) + ", restarted", false,
                   running.process.argv});
  running.child = StartChild(running.process, true);
  ++running.restarts;
  running.last_restart_utime = HostUtime();
}

int ProcessGroup::restarts(const std::string& name) const {
  const Running* running = FindOrNull(name);
  return running == nullptr ? 0 : running->restarts;
}

int64_t ProcessGroup::last_restart_utime(const std::string& name) const {
  const Running* running = FindOrNull(name);
  return running == nullptr ? 0 : running->last_restart_utime;
}

const ProcessGroup::Running* ProcessGroup::FindOrNull(const std::string& name) const {
  const auto found = std::find_if(running_.begin(), running_.end(),
                                  [&](const Running& r) { return r.process.name == name; });
  return found == running_.end() ? nullptr : &*found;
}

ProgramEnd ProcessGroup::Stop(const std::string& name) {
  const auto found = std::find_if(running_.begin(), running_.end(),
                                  [&](const Running& r) { return r.process.name == name; });
  if (found == running_.end()) return {name, "was not running", false, {}};
  const int status = found->child->Stop(kStopGrace);
  ProgramEnd end{name, DescribeExitStatus(status), status == 0, found->process.argv};
  running_.erase(found);
  ends_.push_back(end);
  return end;
}

void ProcessGroup::Signal(const std::string& name, int signal) { Find(name).child->Signal(signal); }

bool ProcessGroup::IsRunning(const std::string& name) {
  const auto found = std::find_if(running_.begin(), running_.end(),
                                  [&](const Running& r) { return r.process.name == name; });
  return found != running_.end() && !found->child->ExitStatus().has_value();
}

void ProcessGroup::StopAll() {
  while (!running_.empty()) Stop(running_.back().process.name);
}

ProgramFailure ProcessGroup::Failure(const Running& running, const std::string& what) const {
  const std::string tail = running.child->Tail(kTailLines);
  const fs::path log = logs_dir_ / (running.process.name + ".log");
  return ProgramFailure(
      running.process.name,
      running.process.name + " (" + running.process.argv.front() + ") " + what +
          (tail.empty() ? "; it printed nothing" : "; its last output:\n" + Indented(tail)) +
          "\n  (whole output: " + log.string() + ")");
}

}  // namespace shapesense
