#include "runtime/devices/serial_port.h"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>

#include "runtime/devices/device_clock.h"

namespace shapesense {
namespace {

std::string ErrnoText() { return std::strerror(errno); }

speed_t BaudConstant(int baud) {
  static const std::map<int, speed_t> kRates = {
      {9600, B9600},     {19200, B19200},   {38400, B38400},   {57600, B57600},
      {115200, B115200}, {230400, B230400}, {460800, B460800}, {921600, B921600}};
  const auto it = kRates.find(baud);
  return it == kRates.end() ? B0 : it->second;
}

// Raw 8N1, receiver on, modem lines ignored, no flow control, reads return at once.
bool SetRawMode(int fd, int baud, std::string* error) {
  termios tty{};
  if (tcgetattr(fd, &tty) != 0) {
    *error = "not a serial port (tcgetattr: " + ErrnoText() + ")";
    return false;
  }
  cfmakeraw(&tty);
  tty.c_cflag |= CLOCAL | CREAD;
  tty.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | CRTSCTS | PARENB);
  tty.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  tty.c_cc[VMIN] = 0;
  tty.c_cc[VTIME] = 0;
  const speed_t speed = BaudConstant(baud);
  if (speed == B0 || cfsetispeed(&tty, speed) != 0 || cfsetospeed(&tty, speed) != 0) {
    *error = "unsupported baud rate " + std::to_string(baud);
    return false;
  }
  if (tcsetattr(fd, TCSANOW, &tty) != 0) {
    *error = "cannot set raw mode (tcsetattr: " + ErrnoText() + ")";
    return false;
  }
  return true;
}

int RemainingMs(int64_t deadline_us) {
  const int64_t left = deadline_us - SteadyMicros();
  return left <= 0 ? 0 : static_cast<int>((left + 999) / 1000);
}

}  // namespace

SerialPort::SerialPort(const std::string& path, int baud) : path_(path) {
  fd_ = open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) throw ActuatorError(path + ": cannot open: " + ErrnoText());
  std::string error;
  if (ioctl(fd_, TIOCEXCL) != 0) {
    error = "cannot take the port exclusively (TIOCEXCL: " + ErrnoText() + ")";
  } else if (SetRawMode(fd_, baud, &error)) {
    tcflush(fd_, TCIOFLUSH);
    return;
  }
  close(fd_);
  fd_ = -1;
  throw ActuatorError(path + ": " + error);
}

SerialPort::~SerialPort() {
  if (fd_ < 0) return;
  // The exclusive flag outlives this descriptor while another one is open
  // (a pty's own end): give it back so a reconnect may open the port again.
  ioctl(fd_, TIOCNXCL);
  close(fd_);
}

void SerialPort::Lost(const std::string& what) const { throw SerialLinkLost(path_ + ": " + what); }

void SerialPort::Write(std::string_view bytes, int64_t deadline_us) {
  while (!bytes.empty()) {
    const ssize_t written = write(fd_, bytes.data(), bytes.size());
    if (written > 0) {
      bytes.remove_prefix(static_cast<size_t>(written));
      continue;
    }
    if (written < 0 && errno != EAGAIN && errno != EINTR)
      Lost("link cut (write: " + ErrnoText() + ")");
    pollfd entry{fd_, POLLOUT, 0};
    const int ready = poll(&entry, 1, RemainingMs(deadline_us));
    if (ready == 0) Lost("the port takes no data (output blocked)");
    if (entry.revents & (POLLHUP | POLLERR)) Lost("link cut (hang-up)");
  }
}

void SerialPort::ReadAvailable(int timeout_ms) {
  pollfd entry{fd_, POLLIN, 0};
  const int ready = poll(&entry, 1, timeout_ms);
  if (ready < 0 && errno != EINTR) Lost("poll: " + ErrnoText());
  if (ready <= 0) return;
  char buffer[512];
  const ssize_t got = read(fd_, buffer, sizeof(buffer));
  if (got > 0) {
    assembler_.Feed(std::string_view(buffer, static_cast<size_t>(got)), &lines_);
    return;
  }
  // A pty whose master closed reads EIO; a tty that went away reads 0 bytes
  // with POLLHUP. Either way nobody is at the other end any more.
  if (got == 0 || (errno != EAGAIN && errno != EINTR)) {
    Lost(got == 0 ? "link cut (hang-up)" : "link cut (read: " + ErrnoText() + ")");
  }
}

std::optional<std::string> SerialPort::ReadLine(int64_t deadline_us) {
  while (next_line_ >= lines_.size()) {
    lines_.clear();
    next_line_ = 0;
    ReadAvailable(RemainingMs(deadline_us));
    if (lines_.empty() && SteadyMicros() >= deadline_us) return std::nullopt;
  }
  return lines_[next_line_++];
}

int SerialPort::DiscardInput() {
  tcflush(fd_, TCIFLUSH);
  int dropped = static_cast<int>(lines_.size() - next_line_);
  lines_.clear();
  next_line_ = 0;
  ReadAvailable(0);  // what arrived between the flush and now, and a hang-up
  dropped += static_cast<int>(lines_.size());
  lines_.clear();
  assembler_.Clear();
  return dropped;
}

PseudoTerminal::PseudoTerminal() {
  termios raw{};
  cfmakeraw(&raw);
  raw.c_cflag |= CLOCAL | CREAD;
  char name[256] = {};
  if (openpty(&master_, &slave_, name, &raw, nullptr) != 0) {
    throw ActuatorError(std::string("cannot make a pseudo-terminal: ") + ErrnoText());
  }
  slave_path_ = name;
  fcntl(master_, F_SETFD, FD_CLOEXEC);
  fcntl(slave_, F_SETFD, FD_CLOEXEC);
  fcntl(master_, F_SETFL, fcntl(master_, F_GETFL) | O_NONBLOCK);
}

PseudoTerminal::~PseudoTerminal() { Close(); }

void PseudoTerminal::Close() {
  if (master_ >= 0) close(master_);
  if (slave_ >= 0) close(slave_);
  master_ = slave_ = -1;
}

}  // namespace shapesense
