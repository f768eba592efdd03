#include "tests/services/capture/fake_v4l2_device.h"

#include <poll.h>
#include <sys/mman.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace shapesense::testing {
namespace {

class FakeDevice : public V4l2Device {
 public:
  explicit FakeDevice(std::shared_ptr<FakeV4l2Driver> driver) : driver_(std::move(driver)) {}
  int Open(const std::string&) override { return driver_->Open(); }
  int Close(int fd) override { return driver_->Close(fd); }
  int Ioctl(int fd, unsigned long request, void* arg) override {
    return driver_->Ioctl(fd, request, arg);
  }
  void* Mmap(size_t length, int fd, int64_t offset) override {
    return driver_->Mmap(length, fd, offset);
  }
  int Munmap(void* start, size_t length) override { return driver_->Munmap(start, length); }
  int Poll(int fd, int, short* revents) override { return driver_->Poll(fd, revents); }
  int64_t EpochMinusMonotonicUs() override { return driver_->EpochMinusMonotonicUs(); }

 private:
  std::shared_ptr<FakeV4l2Driver> driver_;
};

bool IsRaw(uint32_t format) { return format != V4L2_PIX_FMT_MJPEG; }

}  // namespace

std::unique_ptr<V4l2Device> FakeV4l2Driver::MakeDevice() {
  return std::make_unique<FakeDevice>(shared_from_this());
}

void FakeV4l2Driver::AddFrame(std::vector<uint8_t> bytes, int64_t monotonic_us, uint32_t flags) {
  std::lock_guard lock(mutex_);
  frames_.push_back({std::move(bytes), monotonic_us, flags});
}

void FakeV4l2Driver::AddSpuriousWakeup() {
  std::lock_guard lock(mutex_);
  ++spurious_;
}

void FakeV4l2Driver::Unplug() {
  std::lock_guard lock(mutex_);
  plugged_ = false;
}

// A device plugged back is a new device: the old descriptor and buffers are dead.
void FakeV4l2Driver::Replug() {
  std::lock_guard lock(mutex_);
  plugged_ = true;
  open_ = false;
  streaming_ = false;
  buffers_.clear();
  queued_.clear();
  mapped_ = 0;
}

uint32_t FakeV4l2Driver::pixel_format() const {
  std::lock_guard lock(mutex_);
  return format_;
}
uint32_t FakeV4l2Driver::bytes_per_line() const {
  std::lock_guard lock(mutex_);
  v4l2_pix_format pix{};
  FillFormat(&pix);
  return pix.bytesperline;
}
uint32_t FakeV4l2Driver::buffer_count() const {
  std::lock_guard lock(mutex_);
  return static_cast<uint32_t>(buffers_.size());
}
size_t FakeV4l2Driver::queued_buffers() const {
  std::lock_guard lock(mutex_);
  return queued_.size();
}
int FakeV4l2Driver::mapped() const {
  std::lock_guard lock(mutex_);
  return mapped_;
}
bool FakeV4l2Driver::is_open() const {
  std::lock_guard lock(mutex_);
  return open_;
}
bool FakeV4l2Driver::streaming() const {
  std::lock_guard lock(mutex_);
  return streaming_;
}
v4l2_fract FakeV4l2Driver::time_per_frame() const {
  std::lock_guard lock(mutex_);
  return time_per_frame_;
}
std::map<uint32_t, int32_t> FakeV4l2Driver::controls() const {
  std::lock_guard lock(mutex_);
  return controls_;
}

int FakeV4l2Driver::Fail(int error) {
  errno = error;
  return -1;
}

int FakeV4l2Driver::Open() {
  std::lock_guard lock(mutex_);
  if (!plugged_) return Fail(ENOENT);
  if (open_) return Fail(EBUSY);
  open_ = true;
  return kFd;
}

int FakeV4l2Driver::Close(int fd) {
  std::lock_guard lock(mutex_);
  if (fd != kFd || !open_) return Fail(EBADF);
  open_ = false;
  streaming_ = false;
  return 0;
}

void FakeV4l2Driver::FillFormat(v4l2_pix_format* pix) const {
  pix->width = static_cast<uint32_t>(options_.width);
  pix->height = static_cast<uint32_t>(options_.height);
  pix->pixelformat = format_;
  pix->field = V4L2_FIELD_NONE;
  const int bytes_per_pixel = format_ == V4L2_PIX_FMT_YUYV ? 2 : 3;
  pix->bytesperline =
      IsRaw(format_)
          ? static_cast<uint32_t>(options_.width * bytes_per_pixel + options_.row_padding)
          : 0;
  pix->sizeimage = IsRaw(format_) ? pix->bytesperline * pix->height
                                  : static_cast<uint32_t>(options_.width * options_.height * 3);
}

// Like a real driver: an unknown format becomes the first it has, any size its own.
int FakeV4l2Driver::SetFormat(v4l2_format* format) {
  if (format->type != V4L2_BUF_TYPE_VIDEO_CAPTURE) return Fail(EINVAL);
  if (!buffers_.empty()) return Fail(EBUSY);
  const auto& formats = options_.formats;
  const uint32_t wanted = format->fmt.pix.pixelformat;
  format_ =
      std::find(formats.begin(), formats.end(), wanted) != formats.end() ? wanted : formats.front();
  FillFormat(&format->fmt.pix);
  return 0;
}

int FakeV4l2Driver::RequestBuffers(v4l2_requestbuffers* request) {
  if (request->memory != V4L2_MEMORY_MMAP) return Fail(EINVAL);
  if (streaming_ || mapped_ > 0) return Fail(EBUSY);
  queued_.clear();
  buffers_.clear();
  v4l2_pix_format pix{};
  FillFormat(&pix);
  request->count = std::min(request->count, options_.max_buffers);
  buffers_.assign(request->count, std::vector<uint8_t>(pix.sizeimage));
  return 0;
}

int FakeV4l2Driver::QueryBuffer(v4l2_buffer* buffer) {
  if (buffer->index >= buffers_.size()) return Fail(EINVAL);
  buffer->length = static_cast<uint32_t>(buffers_[buffer->index].size());
  buffer->m.offset = static_cast<uint32_t>(buffer->index * kOffsetStep);
  return 0;
}

int FakeV4l2Driver::QueueBuffer(const v4l2_buffer* buffer) {
  if (buffer->index >= buffers_.size()) return Fail(EINVAL);
  if (std::find(queued_.begin(), queued_.end(), buffer->index) != queued_.end())
    return Fail(EINVAL);
  queued_.push_back(buffer->index);
  return 0;
}

bool FakeV4l2Driver::FrameReady() const {
  return streaming_ && !frames_.empty() && !queued_.empty();
}

int FakeV4l2Driver::DequeueBuffer(v4l2_buffer* buffer) {
  if (!streaming_) return Fail(EINVAL);
  if (spurious_ > 0) {
    --spurious_;
    return Fail(EAGAIN);
  }
  if (!FrameReady()) return Fail(EAGAIN);
  const Frame frame = std::move(frames_.front());
  frames_.pop_front();
  const uint32_t index = queued_.front();
  queued_.pop_front();
  std::vector<uint8_t>& memory = buffers_[index];
  const size_t bytes = std::min(memory.size(), frame.bytes.size());
  std::copy_n(frame.bytes.begin(), bytes, memory.begin());
  buffer->index = index;
  buffer->bytesused = static_cast<uint32_t>(bytes);
  buffer->length = static_cast<uint32_t>(memory.size());
  buffer->flags = frame.flags | options_.timestamp_clock | V4L2_BUF_FLAG_DONE;
  buffer->timestamp.tv_sec = frame.monotonic_us / 1'000'000;
  buffer->timestamp.tv_usec = frame.monotonic_us % 1'000'000;
  buffer->sequence = sequence_++;
  return 0;
}

int FakeV4l2Driver::ParmIoctl(unsigned long request, v4l2_streamparm* parm) {
  if (!options_.time_per_frame) return Fail(ENOTTY);
  if (request == VIDIOC_S_PARM) time_per_frame_ = parm->parm.capture.timeperframe;
  parm->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
  parm->parm.capture.timeperframe = time_per_frame_;
  return 0;
}

int FakeV4l2Driver::SetControl(const v4l2_control* control) {
  if (!options_.exposure_controls) return Fail(EINVAL);
  controls_[control->id] = control->value;
  return 0;
}

int FakeV4l2Driver::IoctlLocked(unsigned long request, void* arg) {
  switch (request) {
    case VIDIOC_QUERYCAP: {
      auto* caps = static_cast<v4l2_capability*>(arg);
      std::memset(caps, 0, sizeof(*caps));
      caps->capabilities = options_.capabilities;
      return 0;
    }
    case VIDIOC_S_FMT:
      return SetFormat(static_cast<v4l2_format*>(arg));
    case VIDIOC_G_PARM:
    case VIDIOC_S_PARM:
      return ParmIoctl(request, static_cast<v4l2_streamparm*>(arg));
    case VIDIOC_S_CTRL:
      return SetControl(static_cast<v4l2_control*>(arg));
    case VIDIOC_REQBUFS:
      return RequestBuffers(static_cast<v4l2_requestbuffers*>(arg));
    case VIDIOC_QUERYBUF:
      return QueryBuffer(static_cast<v4l2_buffer*>(arg));
    case VIDIOC_QBUF:
      return QueueBuffer(static_cast<v4l2_buffer*>(arg));
    case VIDIOC_DQBUF:
      return DequeueBuffer(static_cast<v4l2_buffer*>(arg));
    case VIDIOC_STREAMON:
      if (buffers_.empty()) return Fail(EINVAL);
      streaming_ = true;
      return 0;
    case VIDIOC_STREAMOFF:
      streaming_ = false;
      queued_.clear();
      return 0;
    default:
      return Fail(ENOTTY);
  }
}

int FakeV4l2Driver::Ioctl(int fd, unsigned long request, void* arg) {
  std::lock_guard lock(mutex_);
  if (!plugged_) return Fail(ENODEV);
  if (fd != kFd || !open_) return Fail(EBADF);
  return IoctlLocked(request, arg);
}

void* FakeV4l2Driver::Mmap(size_t length, int fd, int64_t offset) {
  std::lock_guard lock(mutex_);
  const auto index = static_cast<size_t>(offset / kOffsetStep);
  if (!plugged_ || fd != kFd || offset % kOffsetStep != 0 || index >= buffers_.size() ||
      length != buffers_[index].size()) {
    errno = EINVAL;
    return MAP_FAILED;
  }
  ++mapped_;
  return buffers_[index].data();
}

int FakeV4l2Driver::Munmap(void* start, size_t) {
  std::lock_guard lock(mutex_);
  if (start == nullptr || mapped_ == 0) return Fail(EINVAL);
  --mapped_;
  return 0;
}

int FakeV4l2Driver::Poll(int fd, short* revents) {
  std::lock_guard lock(mutex_);
  *revents = 0;
  if (fd != kFd) return Fail(EBADF);
  if (!plugged_)
    *revents = POLLERR | POLLHUP;
  else if (spurious_ > 0 || FrameReady())
    *revents = POLLIN;
  return *revents != 0 ? 1 : 0;
}

}  // namespace shapesense::testing
