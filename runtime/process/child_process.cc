#include "runtime/process/child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string_view>
#include <thread>

namespace shapesense {
namespace {

constexpr int kListenFd = 3;    // SD_LISTEN_FDS_START
constexpr int kPidDigits = 12;  // room for any pid, written in the child

struct Pipe {
  int read = -1;
  int write = -1;
};

// Close-on-exec, so that no other child inherits it (a sibling holding a
// write end would keep the reader from ever seeing the end of the output).
Pipe MakePipe() {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw std::runtime_error("pipe2() failed");
  return {fds[0], fds[1]};
}

// What a child failed at before its program ran, with the errno, sent to
// the parent on the error pipe.
enum class ChildStep : int { kExec, kNetworkNamespace, kUtsNamespace, kHostName };

struct ChildError {
  ChildStep step = ChildStep::kExec;
  int error = 0;  // 0: no failure (the pipe closed on exec without a word)
};

// "<step> failed: <errno text>"; an exec failure as the errno text alone.
std::string Describe(const ChildError& failure) {
  const char* const error = std::strerror(failure.error);
  switch (failure.step) {
    case ChildStep::kNetworkNamespace:
      return std::string("setns() into its network namespace failed: ") + error;
    case ChildStep::kUtsNamespace:
      return std::string("unshare(CLONE_NEWUTS) for its host name failed: ") + error;
    case ChildStep::kHostName:
      return std::string("sethostname() failed: ") + error;
    case ChildStep::kExec:
      break;
  }
  return error;
}

[[noreturn]] void FailChild(int error_fd, ChildStep step) {
  const ChildError failure{step, errno};
  if (write(error_fd, &failure, sizeof(failure)) < 0) _exit(127);
  _exit(127);
}

// Moves the forked child onto its host: network namespace, then host name.
void PlaceChild(const ChildOptions& options, int error_fd) {
  if (options.network_namespace >= 0 && setns(options.network_namespace, CLONE_NEWNET) != 0) {
    FailChild(error_fd, ChildStep::kNetworkNamespace);
  }
  if (options.host_name.empty()) return;
  if (unshare(CLONE_NEWUTS) != 0) FailChild(error_fd, ChildStep::kUtsNamespace);
  if (sethostname(options.host_name.data(), options.host_name.size()) != 0) {
    FailChild(error_fd, ChildStep::kHostName);
  }
}

// In the forked child: only async-signal-safe calls (the environment was
// built before the fork). A failure is reported on `error_fd`.
// Writes the child's pid into LISTEN_PID's value (room made before the
// fork) and puts the socket at fd 3, as systemd does.
void PassListeningSocket(int socket, char* listen_pid_value, int* error_fd) {
  char digits[16];
  int n = 0;
  for (pid_t pid = getpid(); pid > 0; pid /= 10) digits[n++] = static_cast<char>('0' + pid % 10);
  for (int i = 0; i < n; ++i) listen_pid_value[i] = digits[n - 1 - i];
  listen_pid_value[n] = '\0';
  if (*error_fd == kListenFd) *error_fd = fcntl(*error_fd, F_DUPFD_CLOEXEC, kListenFd + 1);
  if (socket == kListenFd) {
    fcntl(kListenFd, F_SETFD, 0);
  } else if (dup2(socket, kListenFd) < 0) {
    FailChild(*error_fd, ChildStep::kExec);
  }
}

[[noreturn]] void ExecChild(char* const* args, char* const* environment,
                            const ChildOptions& options, const Pipe& out, int error_fd,
                            pid_t parent, char* listen_pid_value) {
  if (options.own_process_group) setpgid(0, 0);
  if (options.end_with_parent) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(1);  // the parent died before prctl
  }
  PlaceChild(options, error_fd);
  dup2(out.write, STDOUT_FILENO);
  if (options.capture_stderr) dup2(out.write, STDERR_FILENO);
  if (options.listen_socket >= 0) {
    PassListeningSocket(options.listen_socket, listen_pid_value, &error_fd);
  }
  if (options.nice != 0 && setpriority(PRIO_PROCESS, 0, options.nice) != 0) {
    constexpr char kRefused[] = "nice: priority refused (no privilege); normal priority\n";
    if (write(STDERR_FILENO, kRefused, sizeof(kRefused) - 1) < 0) {
      // nothing more can be said from here
    }
  }
  execve(args[0], args, environment);
  FailChild(error_fd, ChildStep::kExec);
}

// What the child failed at, or {kExec, 0} when its exec succeeded.
ChildError ReadChildError(int fd) {
  ChildError failure;
  ssize_t n;
  do {
    n = read(fd, &failure, sizeof(failure));
  } while (n < 0 && errno == EINTR);
  return n == static_cast<ssize_t>(sizeof(failure)) ? failure : ChildError{};
}

// The parent's environment with `variables` set, as "NAME=value" entries.
std::vector<std::string> ChildEnvironment(
    const std::vector<std::pair<std::string, std::string>>& variables) {
  std::vector<std::string> entries;
  for (char** entry = environ; *entry != nullptr; ++entry) {
    const std::string_view text(*entry);
    const std::string_view name = text.substr(0, text.find('='));
    const bool replaced = std::any_of(variables.begin(), variables.end(),
                                      [&](const auto& variable) { return variable.first == name; });
    if (!replaced) entries.emplace_back(text);
  }
  for (const auto& [name, value] : variables)
    entries.push_back(std::string(name).append("=").append(value));
  return entries;
}

// Pointers into `strings`, ending with nullptr, as exec wants them.
std::vector<char*> ExecArray(const std::vector<std::string>& strings) {
  std::vector<char*> pointers;
  pointers.reserve(strings.size() + 1);
  for (const std::string& text : strings) pointers.push_back(const_cast<char*>(text.c_str()));
  pointers.push_back(nullptr);
  return pointers;
}

}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const ChildOptions& options) {
  if (argv.empty()) throw std::runtime_error("ChildProcess: no program given");
  const std::vector<char*> args = ExecArray(argv);
  std::vector<std::pair<std::string, std::string>> variables = options.environment;
  if (options.listen_socket >= 0) {
    variables.emplace_back("LISTEN_FDS", "1");
    variables.emplace_back("LISTEN_PID", std::string(kPidDigits, ' '));  // the child fills it in
  }
  const std::vector<std::string> environment_entries = ChildEnvironment(variables);
  const std::vector<char*> environment = ExecArray(environment_entries);
  char* listen_pid_value = nullptr;
  for (char* entry : environment) {
    if (entry != nullptr && std::string_view(entry).starts_with("LISTEN_PID=")) {
      listen_pid_value = entry + std::strlen("LISTEN_PID=");
    }
  }
  if (!options.log_file.empty()) log_.open(options.log_file, std::ios::app);
  const Pipe out = MakePipe();
  const Pipe exec_error = MakePipe();
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork() failed");
  if (pid_ == 0) {
    ExecChild(args.data(), environment.data(), options, out, exec_error.write, parent,
              listen_pid_value);
  }
  if (options.own_process_group) setpgid(pid_, pid_);  // either side may be first
  close(out.write);
  close(exec_error.write);
  out_fd_ = out.read;
  const ChildError failure = ReadChildError(exec_error.read);
  close(exec_error.read);
  if (failure.error != 0) {
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
    throw std::runtime_error("cannot start '" + argv[0] + "': " + Describe(failure));
  }
}

ChildProcess::~ChildProcess() {
  Stop();
  if (out_fd_ >= 0) close(out_fd_);
}

// Waits up to `timeout_ms` for output and reads one chunk; false when there
// was none or the child closed its output.
bool ChildProcess::ReadOnce(int timeout_ms) {
  if (out_fd_ < 0) return false;
  pollfd fd{out_fd_, POLLIN, 0};
  if (poll(&fd, 1, timeout_ms) <= 0) return false;
  char buffer[4096];
  const ssize_t n = read(out_fd_, buffer, sizeof(buffer));
  if (n <= 0) {  // the child closed its output: it ended
    close(out_fd_);
    out_fd_ = -1;
    return false;
  }
  output_.append(buffer, static_cast<size_t>(n));
  if (log_.is_open()) log_.write(buffer, n).flush();
  return true;
}

bool ChildProcess::WaitForLine(const std::string& text, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const size_t found = output_.find(text, scanned_);
    if (found != std::string::npos) {
      scanned_ = found + text.size();
      return true;
    }
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(
        deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0 || out_fd_ < 0) return false;
    ReadOnce(static_cast<int>(left.count()));
  }
}

void ChildProcess::ReadAvailable() {
  while (ReadOnce(0)) {
  }
}

std::string ChildProcess::Tail(int lines) const {
  if (lines <= 0) return {};
  std::string_view text(output_);
  while (!text.empty() && text.back() == '\n') text.remove_suffix(1);
  size_t start = text.size();
  for (int i = 0; i < lines; ++i) {
    const size_t newline = start == 0 ? std::string_view::npos : text.rfind('\n', start - 1);
    if (newline == std::string_view::npos) return std::string(text);
    start = newline;
  }
  return std::string(text.substr(start + 1));
}

std::optional<int> ChildProcess::ExitStatus() {
  if (pid_ > 0) {
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == pid_) {
      status_ = status;
      pid_ = -1;
    }
  }
  return status_;
}

void ChildProcess::Signal(int signal) const {
  if (pid_ > 0) kill(pid_, signal);
}

int ChildProcess::Stop(std::chrono::milliseconds grace) { return Stop(SIGTERM, grace); }

int ChildProcess::Stop(int signal, std::chrono::milliseconds grace) {
  if (ExitStatus()) return *status_;
  if (pid_ <= 0) return 0;
  kill(pid_, signal);
  const auto deadline = std::chrono::steady_clock::now() + grace;
  while (!ExitStatus()) {
    if (std::chrono::steady_clock::now() > deadline) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
      pid_ = -1;
      status_ = -1;
      break;
    }
    if (!ReadOnce(20)) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ReadAvailable();
  return *status_;
}

std::string DescribeExitStatus(int status) {
  if (status == -1) return "did not stop and was killed";
  if (WIFEXITED(status)) return "exited with status " + std::to_string(WEXITSTATUS(status));
  if (WIFSIGNALED(status)) {
    const int signal = WTERMSIG(status);
    return "killed by signal " + std::to_string(signal) + " (" + strsignal(signal) + ")";
  }
  return "ended with wait status " + std::to_string(status);
}

}  // namespace shapesense
