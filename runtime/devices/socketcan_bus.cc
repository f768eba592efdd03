#include "runtime/devices/socketcan_bus.h"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "runtime/devices/device_clock.h"

namespace shapesense {
namespace {

constexpr int64_t kSendTimeoutUs = 100'000;

std::string ErrnoText() { return std::strerror(errno); }

// Waits for `events` on `fd` until `deadline_us` (steady); true when ready.
bool WaitFor(int fd, short events, int64_t deadline_us) {
  const int64_t left_us = std::max<int64_t>(0, deadline_us - SteadyMicros());
  const timespec timeout{static_cast<time_t>(left_us / 1'000'000),
                         static_cast<long>((left_us % 1'000'000) * 1000)};
  pollfd entry{fd, events, 0};
  return ppoll(&entry, 1, &timeout, nullptr) > 0;
}

class SocketCanBus : public CanBus {
 public:
  SocketCanBus(int fd, std::string interface) : fd_(fd), interface_(std::move(interface)) {}
  ~SocketCanBus() override { close(fd_); }

  std::string name() const override { return interface_; }

  void Send(const CanFrame& frame) override {
    can_frame raw{};
    raw.can_id = frame.id & CAN_SFF_MASK;
    raw.len = frame.size;
    std::memcpy(raw.data, frame.data.data(), frame.size);
    const int64_t deadline_us = SteadyMicros() + kSendTimeoutUs;
    for (;;) {
      if (write(fd_, &raw, sizeof(raw)) == static_cast<ssize_t>(sizeof(raw))) return;
      if (errno != ENOBUFS && errno != EAGAIN && errno != EINTR) {
        throw CanBusError(interface_ + ": send failed: " + ErrnoText() +
                          (errno == ENETDOWN ? " (ip link set " + interface_ + " up)" : ""));
      }
      if (SteadyMicros() >= deadline_us) {
        throw CanBusError(interface_ +
                          ": transmit queue full for 100 ms: no node acknowledges (check the "
                          "cable, termination and bit rate)");
      }
      WaitFor(fd_, POLLOUT, deadline_us);
    }
  }

  std::optional<CanFrame> Receive(std::chrono::microseconds timeout) override {
    const int64_t deadline_us = SteadyMicros() + timeout.count();
    do {
      can_frame raw{};
      const ssize_t got = read(fd_, &raw, sizeof(raw));
      if (got == static_cast<ssize_t>(sizeof(raw))) {
        if (raw.can_id & CAN_ERR_FLAG) {
          CheckErrorFrame(raw);
          continue;
        }
        if (raw.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) continue;  // not CANopen's
        return ToFrame(raw);
      }
      if (got < 0 && errno != EAGAIN && errno != EINTR) {
        throw CanBusError(interface_ + ": receive failed: " + ErrnoText());
      }
    } while (WaitFor(fd_, POLLIN, deadline_us));
    return std::nullopt;
  }

 private:
  static CanFrame ToFrame(const can_frame& raw) {
    CanFrame frame;
    frame.id = raw.can_id & CAN_SFF_MASK;
    frame.size = std::min<uint8_t>(raw.len, 8);
    std::memcpy(frame.data.data(), raw.data, frame.size);
    return frame;
  }

  void CheckErrorFrame(const can_frame& raw) const {
    if (raw.can_id & CAN_ERR_BUSOFF) {
      throw CanBusError(interface_ +
                        ": bus-off (too many transmit errors: check the cable, "
                        "termination and bit rate)");
    }
  }

  int fd_;
  std::string interface_;
};

std::string CanUnavailable() {
  return "SocketCAN unavailable: this kernel has no CAN support (socket(PF_CAN, SOCK_RAW, "
         "CAN_RAW): " +
         ErrnoText() + "); load the can and can_raw modules, or use driver: simulated";
}

void CheckInterfaceUp(int fd, const std::string& interface) {
  ifreq request{};
  std::strncpy(request.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  if (ioctl(fd, SIOCGIFFLAGS, &request) == 0 && !(request.ifr_flags & IFF_UP)) {
    throw CanBusError(interface + ": interface is down (ip link set " + interface + " up)");
  }
}

void BindSocket(int fd, const std::string& interface) {
  if (interface.empty() || interface.size() >= IFNAMSIZ) {
    throw CanBusError("'" + interface + "': not a valid interface name");
  }
  const unsigned index = if_nametoindex(interface.c_str());
  if (index == 0) {
    throw CanBusError("no CAN interface named '" + interface + "' (real: ip link set " + interface +
                      " up type can bitrate 1000000; virtual: ip link add dev " + interface +
                      " type vcan && ip link set up " + interface + ")");
  }
  CheckInterfaceUp(fd, interface);
  const can_err_mask_t errors = CAN_ERR_BUSOFF;
  setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &errors, sizeof(errors));
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = static_cast<int>(index);
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) != 0) {
    throw CanBusError(interface + ": cannot bind a CAN socket: " + ErrnoText());
  }
}

}  // namespace

std::unique_ptr<CanBus> OpenSocketCanBus(const std::string& interface) {
  const int fd = socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) throw CanBusError(CanUnavailable());
  try {
    BindSocket(fd, interface);
  } catch (const CanBusError&) {
    close(fd);
    throw;
  }
  return std::make_unique<SocketCanBus>(fd, interface);
}

}  // namespace shapesense
