#pragma once

// A fake V4L2 driver behind the V4l2Device seam: one capture device of one
// size, a chosen set of formats, mmap buffers, a frame queue the test fills,
// driver timestamps on a fake monotonic clock, and faults (EAGAIN wake-ups,
// error buffers, a device that is unplugged and plugged back). It checks the
// protocol as a driver would: EBUSY for a second open or for freeing buffers
// that are still mapped, EINVAL for queueing a buffer twice, ...

#include <linux/videodev2.h>

#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

#include "services/capture/v4l2_device.h"

namespace shapesense::testing {

struct FakeV4l2Options {
  std::vector<uint32_t> formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_RGB24,
                                   V4L2_PIX_FMT_BGR24};
  int width = 64;
  int height = 48;
  int row_padding = 0;  // bytes at the end of each raw row (bytesperline > width × bpp)
  uint32_t max_buffers = 4;
  uint32_t capabilities = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
  bool time_per_frame = true;     // VIDIOC_S_PARM supported
  bool exposure_controls = true;  // V4L2_CID_EXPOSURE_* supported
  uint32_t timestamp_clock = V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
  int64_t epoch_minus_monotonic_us = 1'700'000'000'000'000;
};

class FakeV4l2Driver : public std::enable_shared_from_this<FakeV4l2Driver> {
 public:
  explicit FakeV4l2Driver(FakeV4l2Options options = {}) : options_(std::move(options)) {}

  // The device a camera gets; it drives this driver.
  std::unique_ptr<V4l2Device> MakeDevice();

  // A frame the sensor captured, `bytes` in the negotiated format, stamped
  // `monotonic_us`; the next VIDIOC_DQBUF returns it in a queued buffer.
  void AddFrame(std::vector<uint8_t> bytes, int64_t monotonic_us, uint32_t flags = 0);
  // poll() says readable but VIDIOC_DQBUF fails with EAGAIN, once.
  void AddSpuriousWakeup();
  void Unplug();
  void Replug();

  // What the camera set up.
  uint32_t pixel_format() const;
  uint32_t bytes_per_line() const;
  uint32_t buffer_count() const;
  size_t queued_buffers() const;
  int mapped() const;
  bool is_open() const;
  bool streaming() const;
  v4l2_fract time_per_frame() const;
  std::map<uint32_t, int32_t> controls() const;

  // The V4l2Device calls.
  int Open();
  int Close(int fd);
  int Ioctl(int fd, unsigned long request, void* arg);
  void* Mmap(size_t length, int fd, int64_t offset);
  int Munmap(void* start, size_t length);
  int Poll(int fd, short* revents);
  int64_t EpochMinusMonotonicUs() const { return options_.epoch_minus_monotonic_us; }

 private:
  struct Frame {
    std::vector<uint8_t> bytes;
    int64_t monotonic_us;
    uint32_t flags;
  };
  static constexpr int kFd = 42;
  static constexpr int64_t kOffsetStep = 1 << 24;

  int Fail(int error);
  int IoctlLocked(unsigned long request, void* arg);
  int SetFormat(v4l2_format* format);
  int RequestBuffers(v4l2_requestbuffers* request);
  int QueryBuffer(v4l2_buffer* buffer);
  int QueueBuffer(const v4l2_buffer* buffer);
  int DequeueBuffer(v4l2_buffer* buffer);
  int ParmIoctl(unsigned long request, v4l2_streamparm* parm);
  int SetControl(const v4l2_control* control);
  void FillFormat(v4l2_pix_format* pix) const;
  bool FrameReady() const;

  const FakeV4l2Options options_;
  mutable std::mutex mutex_;
  bool plugged_ = true;
  bool open_ = false;
  bool streaming_ = false;
  uint32_t format_ = V4L2_PIX_FMT_YUYV;
  v4l2_fract time_per_frame_{1, 30};
  std::map<uint32_t, int32_t> controls_;
  std::vector<std::vector<uint8_t>> buffers_;
  std::deque<uint32_t> queued_;
  int mapped_ = 0;
  std::deque<Frame> frames_;
  int spurious_ = 0;
  uint32_t sequence_ = 0;
};

}  // namespace shapesense::testing
