#pragma once

// Shared by the runtime, service, replay and e2e tests: a synthetic rig with
// exact ground truth, frame-sets rendered into image messages, and small LCM
// helpers. The services' test options are in service_test_options.h.
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "libs/camera/camera.h"
#include "libs/sim/tube_scene.h"
#include "runtime/lcm/lcm_bus.h"
#include "runtime/lcm/pipeline_stages.h"
#include "shapesense/image_t.hpp"

namespace shapesense::testing {

// A three-camera synthetic rig, its backgrounds, and a renderer.
class TestRig {
 public:
  explicit TestRig(uint32_t seed = 1);

  const Rig& rig() const { return rig_; }
  const std::vector<cv::Mat>& backgrounds() const { return backgrounds_; }
  RigSetup Setup() const { return {rig_, backgrounds_}; }

  // Scene i of a test sequence (a random arc or S-curve, different per i).
  TubeScene Scene(int i) const;
  // The rendered images of scene i, BGR, in rig order.
  std::vector<cv::Mat> Render(int i) const;
  // The images of scene i as the capture service would publish them.
  std::vector<image_t> Messages(int i, int64_t trigger_seq, int64_t trigger_utime,
                                int8_t pixel_format = image_t::PIXEL_BGR8) const;

  // Writes rig.yaml and background/<camera>.png into `folder`.
  void WriteFiles(const std::filesystem::path& folder) const;

 private:
  Rig rig_;
  std::vector<cv::Mat> backgrounds_;
  SceneRenderer renderer_;
  uint32_t seed_;
};

// Sets the trigger, host and header times of a frame-set's messages to `now`
// (rendering takes a while: stamp just before publishing).
void Stamp(std::vector<image_t>* images, int64_t now);

// One image message as a capture service would publish it from a BGR frame.
image_t MakeImageMessage(const cv::Mat& bgr, const std::string& camera, int64_t trigger_seq,
                         int64_t trigger_utime, int8_t pixel_format = image_t::PIXEL_BGR8);

// Centreline RMS both ways (estimate to truth and truth to estimate), mm.
double TwoWayRms(const Polyline& estimate, const Polyline& truth);

// Arbitrary bytes published as if they were a message (LcmBus::Publish's
// duck type), for malformed-message tests.
struct RawBytes {
  std::vector<uint8_t> bytes;
  int encode(void* buffer, int offset, int max) const;
  int getEncodedSize() const { return static_cast<int>(bytes.size()); }
};

template <class Message>
std::vector<uint8_t> Encode(const Message& message) {
  std::vector<uint8_t> bytes(static_cast<size_t>(message.getEncodedSize()));
  message.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  return bytes;
}

// Handles `bus` and calls `poll` until `done` or `timeout` passes; false on timeout.
bool HandleUntil(LcmBus& bus, const std::function<bool()>& done,
                 const std::function<void(int64_t)>& poll = {},
                 std::chrono::milliseconds timeout = std::chrono::seconds(60));

}  // namespace shapesense::testing
