#include "services/capture/v4l2_device.h"

#include <fcntl.h>
#include <libv4l2.h>
#include <poll.h>
#include <sys/mman.h>
#include <time.h>

namespace shapesense {
namespace {

int64_t ClockUs(clockid_t clock) {
  timespec now{};
  clock_gettime(clock, &now);
  return static_cast<int64_t>(now.tv_sec) * 1'000'000 + now.tv_nsec / 1000;
}

class LibV4l2Device : public V4l2Device {
 public:
  int Open(const std::string& path) override {
    return v4l2_open(path.c_str(), O_RDWR | O_NONBLOCK);
  }
  int Close(int fd) override { return v4l2_close(fd); }
  int Ioctl(int fd, unsigned long request, void* arg) override {
    return v4l2_ioctl(fd, request, arg);
  }
  void* Mmap(size_t length, int fd, int64_t offset) override {
    return v4l2_mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset);
  }
  int Munmap(void* start, size_t length) override { return v4l2_munmap(start, length); }
  int Poll(int fd, int timeout_ms, short* revents) override {
    pollfd entry{fd, POLLIN, 0};
    const int ready = poll(&entry, 1, timeout_ms);
    *revents = entry.revents;
    return ready;
  }
  int64_t EpochMinusMonotonicUs() override {
    return ClockUs(CLOCK_REALTIME) - ClockUs(CLOCK_MONOTONIC);
  }
};

}  // namespace

std::unique_ptr<V4l2Device> MakeLibV4l2Device() { return std::make_unique<LibV4l2Device>(); }

}  // namespace shapesense
