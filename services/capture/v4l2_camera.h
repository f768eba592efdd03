#pragma once

// A V4L2 camera (UVC webcams, capture cards, MIPI sensors with a V4L2
// driver): mmap streaming through the V4l2Device seam.
//
// V4L2 cameras run free: in software-trigger mode a trigger is latched and
// served by the first complete frame whose driver timestamp is not older
// than the trigger time (frames nobody asked for are returned to the driver
// unconverted). See docs/capture.md for a rig's set-up.

#include <linux/videodev2.h>

#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "services/capture/camera_backend.h"
#include "services/capture/trigger_queue.h"
#include "services/capture/v4l2_device.h"

namespace shapesense {

class V4l2Camera : public CameraBackend {
 public:
  V4l2Camera(CameraConfig config, std::unique_ptr<V4l2Device> device);
  ~V4l2Camera() override;

  const std::string& name() const override { return config_.name; }
  void Open() override;
  void Close() override;
  bool IsOpen() const override { return open_; }
  void Trigger(int64_t seq, int64_t utime) override;
  bool Grab(std::chrono::milliseconds timeout, CameraFrame* frame) override;
  CameraStats Stats() const override;

 private:
  struct MappedBuffer {
    void* start = nullptr;
    size_t length = 0;
  };

  int Xioctl(unsigned long request, void* arg);
  [[noreturn]] void Fail(const std::string& what) const;
  void CheckCapabilities();
  void SetFormat();
  void SetFrameRate();
  void SetExposure();
  void MapBuffers();
  void StartStreaming();
  void Requeue(v4l2_buffer& buffer);
  bool TakeBuffer(CameraFrame* frame);
  bool Deliver(const v4l2_buffer& buffer, CameraFrame* frame);
  void CountIncomplete();

  const CameraConfig config_;
  const std::unique_ptr<V4l2Device> device_;
  const uint32_t fourcc_;
  int fd_ = -1;
  std::atomic<bool> open_{false};
  bool ever_opened_ = false;
  bool exposure_set_ = false;
  int bytes_per_line_ = 0;
  std::vector<MappedBuffer> buffers_;
  TriggerQueue triggers_;
  mutable std::mutex stats_mutex_;
  CameraStats stats_;
};

// The fourcc of a pixel_format name: YUYV, MJPG (or MJPEG), RGB3, BGR3;
// std::invalid_argument for any other.
uint32_t V4l2FourCc(const std::string& pixel_format);
std::string FourCcName(uint32_t fourcc);

// One driver buffer as 8-bit BGR; an empty Mat when the buffer is short or
// (MJPEG) does not decode to a width × height colour image, so that a
// partial or corrupted frame is never delivered.
cv::Mat ConvertV4l2Buffer(uint32_t fourcc, const uint8_t* data, size_t bytes_used, int width,
                          int height, int bytes_per_line);

// A buffer's time on the epoch, µs: drivers stamp buffers with
// CLOCK_MONOTONIC (V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC); other clocks are not
// comparable across the rig, so those buffers take the host time they were
// dequeued at. Returns nullopt-like 0 in *device_ns for those.
int64_t BufferEpochUtime(const v4l2_buffer& buffer, int64_t epoch_minus_monotonic_us,
                         int64_t host_utime, int64_t* device_ns);

}  // namespace shapesense
