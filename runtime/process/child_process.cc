#include "runtime/process/child_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string_view>
#include <thread>

namespace shapesense {
namespace {

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

// In the forked child: only async-signal-safe calls. An exec failure is
// reported as its errno on `error_fd`.
[[noreturn]] void ExecChild(char* const* args, const ChildOptions& options, const Pipe& out,
                            int error_fd, pid_t parent) {
  if (options.own_process_group) setpgid(0, 0);
  if (options.end_with_parent) {
    prctl(PR_SET_PDEATHSIG, SIGTERM);
    if (getppid() != parent) _exit(1);  // the parent died before prctl
  }
  dup2(out.write, STDOUT_FILENO);
  if (options.capture_stderr) dup2(out.write, STDERR_FILENO);
  if (options.nice != 0 && setpriority(PRIO_PROCESS, 0, options.nice) != 0) {
    constexpr char kRefused[] = "nice: priority refused (no privilege); normal priority\n";
    if (write(STDERR_FILENO, kRefused, sizeof(kRefused) - 1) < 0) {
      // nothing more can be said from here
    }
  }
  execv(args[0], args);
  const int error = errno;
  if (write(error_fd, &error, sizeof(error)) < 0) _exit(127);
  _exit(127);
}

// The child's errno when its exec failed; 0 when it succeeded (the pipe
// closed on exec without a word).
int ExecError(int fd) {
  int error = 0;
  ssize_t n;
  do {
    n = read(fd, &error, sizeof(error));
  } while (n < 0 && errno == EINTR);
  return n == static_cast<ssize_t>(sizeof(error)) ? error : 0;
}

}  // namespace

ChildProcess::ChildProcess(const std::vector<std::string>& argv, const ChildOptions& options) {
  if (argv.empty()) throw std::runtime_error("ChildProcess: no program given");
  std::vector<char*> args;
  args.reserve(argv.size() + 1);
  for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
  args.push_back(nullptr);
  if (!options.log_file.empty()) log_.open(options.log_file, std::ios::app);
  const Pipe out = MakePipe();
  const Pipe exec_error = MakePipe();
  const pid_t parent = getpid();
  pid_ = fork();
  if (pid_ < 0) throw std::runtime_error("fork() failed");
  if (pid_ == 0) ExecChild(args.data(), options, out, exec_error.write, parent);
  if (options.own_process_group) setpgid(pid_, pid_);  // either side may be first
  close(out.write);
  close(exec_error.write);
  out_fd_ = out.read;
  const int error = ExecError(exec_error.read);
  close(exec_error.read);
  if (error != 0) {
    waitpid(pid_, nullptr, 0);
    pid_ = -1;
    throw std::runtime_error("cannot start '" + argv[0] + "': " + std::strerror(error));
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
