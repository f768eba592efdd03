#include "services/capture/v4l2_camera.h"

#include <poll.h>
#include <sys/mman.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

#include "runtime/lcm/lcm_bus.h"

namespace shapesense {
namespace {

using Clock = std::chrono::steady_clock;

int RemainingMs(Clock::time_point deadline) {
  const auto left = std::chrono::ceil<std::chrono::milliseconds>(deadline - Clock::now());
  return static_cast<int>(std::max<int64_t>(0, left.count()));
}

v4l2_buffer EmptyBuffer() {
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  return buffer;
}

cv::Mat DecodeJpeg(const uint8_t* data, size_t bytes, int width, int height) {
  if (bytes < 4) return {};
  // imdecode reads but never writes; the Mat header only wraps the driver's buffer.
  const cv::Mat stream(1, static_cast<int>(bytes), CV_8U, const_cast<uint8_t*>(data));
  cv::Mat image;
  try {
    image = cv::imdecode(stream, cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    return {};
  }
  if (image.cols != width || image.rows != height) return {};
  return image;
}

}  // namespace

uint32_t V4l2FourCc(const std::string& pixel_format) {
  if (pixel_format == "YUYV") return V4L2_PIX_FMT_YUYV;
  if (pixel_format == "MJPG" || pixel_format == "MJPEG") return V4L2_PIX_FMT_MJPEG;
  if (pixel_format == "RGB3") return V4L2_PIX_FMT_RGB24;
  if (pixel_format == "BGR3") return V4L2_PIX_FMT_BGR24;
  throw std::invalid_argument("pixel_format: expected YUYV, MJPG, RGB3 or BGR3, got '" +
                              pixel_format + "'");
}

std::string FourCcName(uint32_t fourcc) {
  std::string name;
  for (int shift = 0; shift < 32; shift += 8) name += static_cast<char>((fourcc >> shift) & 0xff);
  return name;
}

cv::Mat ConvertV4l2Buffer(uint32_t fourcc, const uint8_t* data, size_t bytes_used, int width,
                          int height, int bytes_per_line) {
  if (fourcc == V4L2_PIX_FMT_MJPEG || fourcc == V4L2_PIX_FMT_JPEG) {
    return DecodeJpeg(data, bytes_used, width, height);
  }
  const int bytes_per_pixel = fourcc == V4L2_PIX_FMT_YUYV ? 2 : 3;
  const size_t row = static_cast<size_t>(std::max(bytes_per_line, width * bytes_per_pixel));
  if (bytes_used <
      row * static_cast<size_t>(height - 1) + static_cast<size_t>(width) * bytes_per_pixel) {
    return {};
  }
  void* pixels = const_cast<uint8_t*>(data);  // read only; converted into a new image
  cv::Mat bgr;
  if (fourcc == V4L2_PIX_FMT_YUYV) {
    cv::cvtColor(cv::Mat(height, width, CV_8UC2, pixels, row), bgr, cv::COLOR_YUV2BGR_YUYV);
  } else if (fourcc == V4L2_PIX_FMT_RGB24) {
    cv::cvtColor(cv::Mat(height, width, CV_8UC3, pixels, row), bgr, cv::COLOR_RGB2BGR);
  } else if (fourcc == V4L2_PIX_FMT_BGR24) {
    bgr = cv::Mat(height, width, CV_8UC3, pixels, row).clone();
  }
  return bgr;
}

int64_t BufferEpochUtime(const v4l2_buffer& buffer, int64_t epoch_minus_monotonic_us,
                         int64_t host_utime, int64_t* device_ns) {
  if ((buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) != V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
    *device_ns = 0;
    return host_utime;
  }
  const int64_t monotonic_us =
      static_cast<int64_t>(buffer.timestamp.tv_sec) * 1'000'000 + buffer.timestamp.tv_usec;
  const int64_t epoch_us = monotonic_us + epoch_minus_monotonic_us;
  *device_ns = epoch_us * 1000;
  return epoch_us;
}

V4l2Camera::V4l2Camera(CameraConfig config, std::unique_ptr<V4l2Device> device)
    : config_(std::move(config)),
      device_(std::move(device)),
      fourcc_(V4l2FourCc(config_.pixel_format)) {}

V4l2Camera::~V4l2Camera() { Close(); }

int V4l2Camera::Xioctl(unsigned long request, void* arg) {
  int result = 0;
  do {
    result = device_->Ioctl(fd_, request, arg);
  } while (result < 0 && errno == EINTR);
  return result;
}

void V4l2Camera::Fail(const std::string& what) const {
  throw CameraError(config_.name + ": " + config_.device + ": " + what);
}

void V4l2Camera::CheckCapabilities() {
  v4l2_capability caps{};
  if (Xioctl(VIDIOC_QUERYCAP, &caps) < 0) {
    Fail(std::string("not a V4L2 device (VIDIOC_QUERYCAP: ") + std::strerror(errno) + ")");
  }
  const uint32_t device_caps =
      (caps.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? caps.device_caps : caps.capabilities;
  if ((device_caps & V4L2_CAP_VIDEO_CAPTURE) == 0) Fail("not a video capture device");
  if ((device_caps & V4L2_CAP_STREAMING) == 0) Fail("the driver cannot stream (no mmap I/O)");
}

// Drivers adjust a format they cannot give instead of failing; a camera
// that does not deliver exactly the calibrated size and format is an error.
void V4l2Camera::SetFormat() {
  v4l2_format format{};
  format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  format.fmt.pix.width = static_cast<uint32_t>(config_.width);
  format.fmt.pix.height = static_cast<uint32_t>(config_.height);
  format.fmt.pix.pixelformat = fourcc_;
  format.fmt.pix.field = V4L2_FIELD_NONE;
  if (Xioctl(VIDIOC_S_FMT, &format) < 0) Fail(std::string("VIDIOC_S_FMT: ") + std::strerror(errno));
  const v4l2_pix_format& got = format.fmt.pix;
  if (got.pixelformat != fourcc_ || static_cast<int>(got.width) != config_.width ||
      static_cast<int>(got.height) != config_.height) {
    Fail("cannot deliver " + std::to_string(config_.width) + "x" + std::to_string(config_.height) +
         " " + FourCcName(fourcc_) + " (the driver offers " + std::to_string(got.width) + "x" +
         std::to_string(got.height) + " " + FourCcName(got.pixelformat) + ")");
  }
  bytes_per_line_ = static_cast<int>(got.bytesperline);
}

// Not every driver can set a frame rate; the camera then runs at its own.
void V4l2Camera::SetFrameRate() {
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (Xioctl(VIDIOC_G_PARM, &parm) < 0 ||
      (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) == 0) {
    return;
  }
  parm.parm.capture.timeperframe.numerator = 1000;
  parm.parm.capture.timeperframe.denominator =
      static_cast<uint32_t>(std::lround(config_.frame_rate * 1000.0));
  Xioctl(VIDIOC_S_PARM, &parm);
}

// Manual exposure where the driver has the controls (UVC: units of 100 µs);
// gain has no common unit across V4L2 drivers and is left to the camera.
void V4l2Camera::SetExposure() {
  v4l2_control mode{V4L2_CID_EXPOSURE_AUTO, V4L2_EXPOSURE_MANUAL};
  v4l2_control exposure{V4L2_CID_EXPOSURE_ABSOLUTE,
                        static_cast<int32_t>(std::lround(config_.exposure_us / 100.0))};
  exposure_set_ = Xioctl(VIDIOC_S_CTRL, &mode) == 0 && Xioctl(VIDIOC_S_CTRL, &exposure) == 0;
}

void V4l2Camera::MapBuffers() {
  v4l2_requestbuffers request{};
  request.count = static_cast<uint32_t>(config_.buffer_count);
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (Xioctl(VIDIOC_REQBUFS, &request) < 0)
    Fail(std::string("VIDIOC_REQBUFS: ") + std::strerror(errno));
  if (request.count < 2)
    Fail("the driver gave " + std::to_string(request.count) + " buffers, need 2");
  for (uint32_t i = 0; i < request.count; ++i) {
    v4l2_buffer buffer = EmptyBuffer();
    buffer.index = i;
    if (Xioctl(VIDIOC_QUERYBUF, &buffer) < 0)
      Fail(std::string("VIDIOC_QUERYBUF: ") + std::strerror(errno));
    void* start = device_->Mmap(buffer.length, fd_, buffer.m.offset);
    if (start == MAP_FAILED) Fail(std::string("mmap: ") + std::strerror(errno));
    buffers_.push_back({start, buffer.length});
  }
}

void V4l2Camera::StartStreaming() {
  for (uint32_t i = 0; i < buffers_.size(); ++i) {
    v4l2_buffer buffer = EmptyBuffer();
    buffer.index = i;
    if (Xioctl(VIDIOC_QBUF, &buffer) < 0) Fail(std::string("VIDIOC_QBUF: ") + std::strerror(errno));
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (Xioctl(VIDIOC_STREAMON, &type) < 0)
    Fail(std::string("VIDIOC_STREAMON: ") + std::strerror(errno));
}

void V4l2Camera::Open() {
  Close();
  fd_ = device_->Open(config_.device);
  if (fd_ < 0) {
    const int error = errno;
    // libv4l2 queries the capabilities inside v4l2_open: ENOTTY there means no V4L2 device.
    Fail(std::string("cannot open: ") + std::strerror(error) +
         (error == ENOTTY ? " (not a V4L2 device)" : ""));
  }
  try {
    CheckCapabilities();
    SetFormat();
    SetFrameRate();
    SetExposure();
    MapBuffers();
    StartStreaming();
  } catch (const CameraError&) {
    Close();
    throw;
  }
  std::lock_guard lock(stats_mutex_);
  if (ever_opened_) ++stats_.reconnects;
  ever_opened_ = true;
  open_ = true;
}

// Also after the device vanished: every step may fail, and each is still needed
// to release the mappings and the descriptor.
void V4l2Camera::Close() {
  open_ = false;
  if (fd_ < 0) return;
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  Xioctl(VIDIOC_STREAMOFF, &type);
  for (const MappedBuffer& buffer : buffers_) device_->Munmap(buffer.start, buffer.length);
  buffers_.clear();
  v4l2_requestbuffers release{};
  release.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  release.memory = V4L2_MEMORY_MMAP;
  Xioctl(VIDIOC_REQBUFS, &release);
  device_->Close(fd_);
  fd_ = -1;
  triggers_.Clear();
}

void V4l2Camera::Trigger(int64_t seq, int64_t utime) {
  if (open_) triggers_.Push({seq, utime});
}

bool V4l2Camera::Grab(std::chrono::milliseconds timeout, CameraFrame* frame) {
  if (!open_) Fail("not open");
  const Clock::time_point deadline = Clock::now() + timeout;
  for (;;) {
    short revents = 0;
    const int ready = device_->Poll(fd_, RemainingMs(deadline), &revents);
    if (ready < 0 && errno != EINTR) Fail(std::string("lost (poll: ") + std::strerror(errno) + ")");
    if (ready > 0 && (revents & (POLLERR | POLLHUP | POLLNVAL)) != 0)
      Fail("lost (the device reports an error)");
    if (ready > 0 && TakeBuffer(frame)) return true;
    if (ready == 0 || Clock::now() >= deadline) break;
  }
  std::lock_guard lock(stats_mutex_);
  ++stats_.timeouts;
  return false;
}

void V4l2Camera::Requeue(v4l2_buffer& buffer) {
  if (Xioctl(VIDIOC_QBUF, &buffer) < 0)
    Fail(std::string("lost (VIDIOC_QBUF: ") + std::strerror(errno) + ")");
}

// Dequeues one buffer; true when it became `frame`. Every buffer goes back to
// the driver, delivered or not.
bool V4l2Camera::TakeBuffer(CameraFrame* frame) {
  v4l2_buffer buffer = EmptyBuffer();
  if (Xioctl(VIDIOC_DQBUF, &buffer) < 0) {
    if (errno == EAGAIN) return false;
    Fail(std::string("lost (VIDIOC_DQBUF: ") + std::strerror(errno) + ")");
  }
  if (buffer.index >= buffers_.size()) Fail("the driver returned an unknown buffer");
  const bool delivered = Deliver(buffer, frame);
  Requeue(buffer);
  return delivered;
}

bool V4l2Camera::Deliver(const v4l2_buffer& buffer, CameraFrame* frame) {
  if ((buffer.flags & V4L2_BUF_FLAG_ERROR) != 0) {
    CountIncomplete();
    return false;
  }
  const int64_t host_utime = NowUtime();
  int64_t device_ns = 0;
  const int64_t stamp =
      BufferEpochUtime(buffer, device_->EpochMinusMonotonicUs(), host_utime, &device_ns);
  std::optional<QueuedTrigger> trigger;
  if (config_.Trigger() == TriggerMode::kSoftware) {
    trigger = triggers_.Front(std::chrono::milliseconds(0));
    // A frame exposed before the oldest pending trigger (or with none pending) is not wanted.
    if (!trigger || stamp < trigger->utime) return false;
  }
  cv::Mat image =
      ConvertV4l2Buffer(fourcc_, static_cast<const uint8_t*>(buffers_[buffer.index].start),
                        buffer.bytesused, config_.width, config_.height, bytes_per_line_);
  if (image.empty()) {
    CountIncomplete();  // a pending trigger stays for the next, later frame
    return false;
  }
  if (trigger) triggers_.PopFront(trigger->seq);
  frame->image = std::move(image);
  frame->frame_id = buffer.sequence;
  frame->trigger_seq = trigger ? trigger->seq : -1;
  frame->trigger_utime = trigger ? trigger->utime : stamp;
  frame->device_timestamp_ns = device_ns;
  frame->host_utime = NowUtime();
  frame->exposure_us = exposure_set_ ? config_.exposure_us : 0.0;
  frame->gain_db = 0.0;
  std::lock_guard lock(stats_mutex_);
  ++stats_.frames;
  return true;
}

void V4l2Camera::CountIncomplete() {
  std::lock_guard lock(stats_mutex_);
  ++stats_.incomplete;
}

CameraStats V4l2Camera::Stats() const {
  std::lock_guard lock(stats_mutex_);
  CameraStats stats = stats_;
  stats.missed_triggers = triggers_.Dropped();
  return stats;
}

}  // namespace shapesense
