#include "tests/support/test_rig.h"

#include <algorithm>
#include <cstring>
#include <numbers>

#include "libs/geometry/polyline.h"
#include "libs/sim/scene_generators.h"
#include "runtime/dataset.h"
#include "runtime/lcm/image_codec.h"
#include "runtime/lcm/stage_times.h"

namespace shapesense::testing {
namespace {

Rig MakeRig(uint32_t seed) {
  SyntheticRigOptions options;
  options.seed = seed;
  return MakeSyntheticRig(options);
}

std::vector<cv::Mat> RenderBackgrounds(const SceneRenderer& renderer, const Rig& rig,
                                       uint32_t seed) {
  const TubeScene scene = RandomScene(rig, seed, 1.0);
  std::vector<cv::Mat> backgrounds;
  for (const RenderedView& view : renderer.Render(scene, RenderOptions{}, seed)) {
    backgrounds.push_back(view.background);
  }
  return backgrounds;
}

}  // namespace

TestRig::TestRig(uint32_t seed) : rig_(MakeRig(seed)), renderer_(rig_), seed_(seed) {
  backgrounds_ = RenderBackgrounds(renderer_, rig_, seed);
}

TubeScene TestRig::Scene(int i) const {
  return RandomScene(rig_, seed_ * 1000 + static_cast<uint32_t>(i),
                     150.0 * std::numbers::pi / 180.0, 3);
}

std::vector<cv::Mat> TestRig::Render(int i) const {
  std::vector<cv::Mat> images;
  for (const RenderedView& view :
       renderer_.Render(Scene(i), RenderOptions{}, seed_ + static_cast<uint32_t>(i))) {
    images.push_back(view.image);
  }
  return images;
}

std::vector<image_t> TestRig::Messages(int i, int64_t trigger_seq, int64_t trigger_utime,
                                       int8_t pixel_format) const {
  const std::vector<cv::Mat> images = Render(i);
  std::vector<image_t> messages;
  for (size_t k = 0; k < images.size(); ++k) {
    messages.push_back(MakeImageMessage(images[k], rig_.cameras[k].name, trigger_seq, trigger_utime,
                                        pixel_format));
  }
  return messages;
}

void TestRig::WriteFiles(const std::filesystem::path& folder) const {
  WriteDatasetHeader(folder, rig_, backgrounds_);
}

void Stamp(std::vector<image_t>* images, int64_t now) {
  for (image_t& image : *images) {
    image.trigger_utime = now;
    image.host_utime = now;
    image.header.utime = now;
    for (stage_time_t& stage : image.stage_times) stage.end_utime = now;
  }
}

image_t MakeImageMessage(const cv::Mat& bgr, const std::string& camera, int64_t trigger_seq,
                         int64_t trigger_utime, int8_t pixel_format) {
  cv::Mat pixels = bgr;
  if (pixel_format >= image_t::PIXEL_BAYER_RG8 && pixel_format <= image_t::PIXEL_BAYER_BG8) {
    pixels = MosaicBayer(bgr, pixel_format);
  }
  image_t image = ImageToMessage(pixels, pixel_format);
  image.camera = camera;
  image.trigger_seq = trigger_seq;
  image.trigger_utime = trigger_utime;
  image.host_utime = NowUtime();
  image.header.utime = image.host_utime;
  image.stage_times.push_back(MakeStageTime("capture", 1500, image.host_utime));
  image.num_stage_times = 1;
  return image;
}

double TwoWayRms(const Polyline& estimate, const Polyline& truth) {
  return std::max(RmsDistanceToPolyline(estimate, truth), RmsDistanceToPolyline(truth, estimate));
}

int RawBytes::encode(void* buffer, int offset, int max) const {
  if (max < static_cast<int>(bytes.size())) return -1;
  if (!bytes.empty())
    std::memcpy(static_cast<uint8_t*>(buffer) + offset, bytes.data(), bytes.size());
  return static_cast<int>(bytes.size());
}

bool HandleUntil(LcmBus& bus, const std::function<bool()>& done,
                 const std::function<void(int64_t)>& poll, std::chrono::milliseconds timeout) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    bus.Handle(10);
    if (poll) poll(NowUtime());
  }
  return true;
}

}  // namespace shapesense::testing
