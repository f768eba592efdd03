#include "tests/services/capture/aravis/fake_gige_camera.h"

#include <arv.h>

#include <cstring>
#include <opencv2/imgproc.hpp>

namespace shapesense::nettest {
namespace {

// Called by the camera's thread for every image, in the client's format.
void Fill(ArvBuffer* buffer, void* camera, guint32 /*exposure*/, guint32 /*gain*/,
          ArvPixelFormat format) {
  const size_t size = static_cast<size_t>(arv_buffer_get_image_width(buffer)) *
                      arv_buffer_get_image_height(buffer) * ARV_PIXEL_FORMAT_BIT_PER_PIXEL(format) /
                      8;
  // The buffer is the camera's own; the fill callback is where it is written.
  void* data = const_cast<void*>(arv_buffer_get_data(buffer, nullptr));
  static_cast<FakeGigeCamera*>(camera)->FillNext(data, size);
}

}  // namespace

std::vector<uint8_t> PatternBytes(int64_t n, size_t size) {
  std::vector<uint8_t> bytes(size);
  uint64_t state = 0x9e3779b97f4a7c15ULL * static_cast<uint64_t>(n + 1);
  for (size_t i = 0; i < size; ++i) {
    state = state * 6364136223846793005ULL + 1442695040888963407ULL;
    bytes[i] = static_cast<uint8_t>(state >> 56);
  }
  for (size_t i = 0; i < 4 && i < size; ++i) bytes[i] = static_cast<uint8_t>(n >> (8 * i));
  return bytes;
}

std::vector<uint8_t> RawBytesOf(const cv::Mat& image) {
  cv::Mat raw;
  if (image.channels() == 3) {
    cv::cvtColor(image, raw, cv::COLOR_BGR2RGB);
  } else {
    raw = image.clone();
  }
  return std::vector<uint8_t>(raw.datastart, raw.dataend);
}

int64_t FrameNumberOf(const std::vector<uint8_t>& raw) {
  int64_t n = 0;
  for (size_t i = 0; i < 4 && i < raw.size(); ++i) n |= static_cast<int64_t>(raw[i]) << (8 * i);
  return n;
}

FakeGigeCamera::FakeGigeCamera(const std::string& address, const std::string& serial)
    : camera_(arv_gv_fake_camera_new(address.c_str(), serial.c_str())) {
  ArvFakeCamera* fake = arv_gv_fake_camera_get_fake_camera(camera_);
  arv_fake_camera_set_trigger_frequency(fake, 1000.0);
  arv_fake_camera_set_fill_pattern(fake, &Fill, this);
}

FakeGigeCamera::~FakeGigeCamera() { g_object_unref(camera_); }

bool FakeGigeCamera::running() const { return arv_gv_fake_camera_is_running(camera_); }

void FakeGigeCamera::SetPacketLoss(double ratio) {
  g_object_set(camera_, "gvsp-lost-ratio", ratio, nullptr);
}

uint32_t FakeGigeCamera::Register(uint32_t address) const {
  guint32 value = 0;
  arv_fake_camera_read_register(arv_gv_fake_camera_get_fake_camera(camera_), address, &value);
  return value;
}

std::vector<int64_t> FakeGigeCamera::FillTimes() const {
  std::lock_guard lock(mutex_);
  return fill_times_;
}

void FakeGigeCamera::FillNext(void* data, size_t size) {
  std::lock_guard lock(mutex_);
  const std::vector<uint8_t> bytes = PatternBytes(static_cast<int64_t>(fill_times_.size()), size);
  fill_times_.push_back(g_get_real_time());
  std::memcpy(data, bytes.data(), bytes.size());
}

}  // namespace shapesense::nettest
