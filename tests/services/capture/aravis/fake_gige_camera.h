#pragma once

// A real GigE Vision camera in the test process (Aravis's ArvGvFakeCamera)
// whose images the test can check byte for byte.

#include <cstddef>
#include <cstdint>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

struct _ArvGvFakeCamera;

namespace shapesense::nettest {

// Frame n (the camera's n-th image, from 0) holds PatternBytes(n, size): a
// pseudo-random byte per position, but for bytes 0-3 that hold n (little
// endian), so a received image tells which frame it is.
std::vector<uint8_t> PatternBytes(int64_t n, size_t size);

// The raw bytes of a decoded RGB8 (given as BGR) or Mono8 image.
std::vector<uint8_t> RawBytesOf(const cv::Mat& image);

// The frame number stored in raw bytes 0-3.
int64_t FrameNumberOf(const std::vector<uint8_t>& raw);

class FakeGigeCamera {
 public:
  // Serves on `address` (an address of an interface, e.g. 127.0.0.2) as
  // device "Aravis-Fake-<serial>". It answers software triggers within 1 ms.
  FakeGigeCamera(const std::string& address, const std::string& serial);
  ~FakeGigeCamera();
  FakeGigeCamera(const FakeGigeCamera&) = delete;
  FakeGigeCamera& operator=(const FakeGigeCamera&) = delete;

  bool running() const;
  // The fraction of stream packets (leader, data, trailer) it drops.
  void SetPacketLoss(double ratio);
  // A register of the camera (ARV_FAKE_CAMERA_REGISTER_*).
  uint32_t Register(uint32_t address) const;

  // Host time (µs since epoch) of each image it made, by frame number.
  std::vector<int64_t> FillTimes() const;

  // Writes the next frame's pattern (called by the camera's thread).
  void FillNext(void* data, size_t size);

 private:
  _ArvGvFakeCamera* camera_ = nullptr;
  mutable std::mutex mutex_;
  std::vector<int64_t> fill_times_;
};

}  // namespace shapesense::nettest
