#include "tests/runtime/process/notify_socket.h"

#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <stdexcept>

namespace shapesense::testing {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

fs::path FreshFolder() {
  static int count = 0;
  fs::path folder = fs::temp_directory_path() / ("shapesense_notify_" + std::to_string(getpid()) +
                                                 "_" + std::to_string(count++));
  fs::remove_all(folder);
  fs::create_directories(folder);
  return folder;
}

int BoundDatagramSocket(const fs::path& path) {
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const int fd = path.string().size() < sizeof(address.sun_path)
                     ? ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0)
                     : -1;
  if (fd < 0) throw std::runtime_error("notify socket: cannot create " + path.string());
  std::strncpy(address.sun_path, path.c_str(), sizeof(address.sun_path) - 1);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof(address)) != 0) {
    ::close(fd);
    throw std::runtime_error("notify socket: cannot bind " + path.string() + ": " +
                             std::strerror(errno));
  }
  return fd;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

bool Has(const std::vector<std::string>& lines, const std::string& state) {
  return std::find(lines.begin(), lines.end(), state) != lines.end();
}

}  // namespace

NotifySocket::NotifySocket(long watchdog_usec)
    : folder_(FreshFolder()), fd_(BoundDatagramSocket(folder_ / "notify")) {
  ::setenv("NOTIFY_SOCKET", (folder_ / "notify").c_str(), 1);
  ::unsetenv("WATCHDOG_PID");
  if (watchdog_usec > 0) {
    ::setenv("WATCHDOG_USEC", std::to_string(watchdog_usec).c_str(), 1);
  } else {
    ::unsetenv("WATCHDOG_USEC");
  }
}

NotifySocket::~NotifySocket() {
  ::unsetenv("NOTIFY_SOCKET");
  ::unsetenv("WATCHDOG_USEC");
  ::unsetenv("WATCHDOG_PID");
  ::close(fd_);
  std::error_code ignored;
  fs::remove_all(folder_, ignored);
}

std::vector<std::string> NotifySocket::Receive(std::chrono::milliseconds timeout) {
  pollfd waiting{fd_, POLLIN, 0};
  if (::poll(&waiting, 1, static_cast<int>(std::max<int64_t>(timeout.count(), 0))) <= 0) return {};
  std::array<char, 4096> buffer{};
  const ssize_t size = ::recv(fd_, buffer.data(), buffer.size(), MSG_DONTWAIT);
  if (size <= 0) return {};
  std::vector<std::string> lines = Lines(std::string(buffer.data(), static_cast<size_t>(size)));
  lines_.insert(lines_.end(), lines.begin(), lines.end());
  return lines;
}

bool NotifySocket::WaitFor(const std::string& state, std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  while (Clock::now() < end) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now());
    if (Has(Receive(left), state)) return true;
  }
  return false;
}

int NotifySocket::Count(const std::string& state, std::chrono::milliseconds window) {
  const auto end = Clock::now() + window;
  int count = 0;
  while (Clock::now() < end) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now());
    if (Has(Receive(left), state)) ++count;
  }
  return count;
}

void NotifySocket::Drain() {
  while (!Receive(std::chrono::milliseconds(0)).empty()) {
  }
}

std::string NotifySocket::Transcript() const {
  std::string text;
  for (const std::string& line : lines_) text += line + '\n';
  return text;
}

}  // namespace shapesense::testing
