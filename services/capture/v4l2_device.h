#pragma once

// The system calls the V4L2 backend makes, behind a seam: the real device
// goes through libv4l2 (which also converts formats a camera lacks), and the
// tests put a fake driver in its place (the build machine's kernel has no
// V4L2). Each call returns what the system call returns, with errno set on
// failure, so the backend's error handling is the same for both.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

namespace shapesense {

class V4l2Device {
 public:
  virtual ~V4l2Device() = default;

  // open(path, O_RDWR | O_NONBLOCK): a descriptor, or -1.
  virtual int Open(const std::string& path) = 0;
  virtual int Close(int fd) = 0;
  // ioctl(fd, request, arg): 0 (or a positive value), or -1.
  virtual int Ioctl(int fd, unsigned long request, void* arg) = 0;
  // mmap(nullptr, length, PROT_READ | PROT_WRITE, MAP_SHARED, fd, offset): MAP_FAILED on failure.
  virtual void* Mmap(size_t length, int fd, int64_t offset) = 0;
  virtual int Munmap(void* start, size_t length) = 0;
  // poll() on one descriptor for input: > 0 with `revents` set, 0 on timeout, -1 on error.
  virtual int Poll(int fd, int timeout_ms, short* revents) = 0;
  // CLOCK_REALTIME minus CLOCK_MONOTONIC now, µs: places the drivers'
  // monotonic buffer timestamps on the epoch.
  virtual int64_t EpochMinusMonotonicUs() = 0;
};

// The real device: libv4l2 (v4l2_open, v4l2_ioctl, v4l2_mmap, ...) and poll().
std::unique_ptr<V4l2Device> MakeLibV4l2Device();

}  // namespace shapesense
