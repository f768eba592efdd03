#include "tests/bench/latency_bench_rig.h"

#include <algorithm>
#include <thread>

#include "libs/sim/scene_generators.h"
#include "libs/sim/trajectory.h"
#include "runtime/dataset.h"
#include "runtime/lcm/channels.h"
#include "services/capture/image_message.h"

namespace shapesense::bench {
namespace {

Rig MakeRig(const BenchRigOptions& options) {
  SyntheticRigOptions rig;
  rig.image_width = options.width;
  rig.image_height = options.height;
  // The same field of view at any size, so the manipulator fills the same
  // share of every image.
  rig.focal_px *= static_cast<double>(options.width) / 640.0;
  rig.seed = 3;
  return MakeSyntheticRig(rig);
}

// The camera messages of one rendered view, as CaptureService::PublishFrame
// builds them (trigger and times are stamped when publishing).
std::vector<image_t> ToMessages(const Rig& rig, const std::vector<RenderedView>& views) {
  std::vector<image_t> messages;
  for (size_t k = 0; k < views.size(); ++k) {
    CameraFrame frame;
    frame.image = views[k].image;
    messages.push_back(ToImageMessage(rig.cameras[k].name, frame, 0, 0, ImageCompression::kNone));
  }
  return messages;
}

// Renders sets [first, end) with stride `step` (one rendering thread's share).
void RenderShare(const Rig& rig, const SceneRenderer& renderer, const TrajectoryOptions& motion,
                 size_t first, size_t step, BenchRig* out) {
  const size_t count = out->frame_sets.size();
  for (size_t i = first; i < count; i += step) {
    const double t = motion.loop_period * static_cast<double>(i) / static_cast<double>(count);
    const std::vector<RenderedView> views =
        renderer.Render(SceneAt(motion, rig, t), motion.render, 100 + static_cast<uint32_t>(i));
    out->frame_sets[i] = ToMessages(rig, views);
    if (i == 0) {
      for (const RenderedView& view : views) out->backgrounds.push_back(view.background);
    }
  }
}

}  // namespace

BenchRig MakeBenchRig(const BenchRigOptions& options) {
  BenchRig out;
  out.rig = MakeRig(options);
  out.frame_sets.resize(static_cast<size_t>(std::max(options.frame_sets, 1)));
  const SceneRenderer renderer(out.rig);
  const TrajectoryOptions motion;  // the rig-sim's built-in sweep
  const size_t threads = static_cast<size_t>(std::clamp(options.threads, 1, 16));
  std::vector<std::thread> workers;
  for (size_t first = 0; first < threads; ++first) {
    workers.emplace_back(
        [&, first] { RenderShare(out.rig, renderer, motion, first, threads, &out); });
  }
  for (std::thread& worker : workers) worker.join();
  return out;
}

void WriteBenchRig(const BenchRig& bench_rig, const std::filesystem::path& folder) {
  WriteDatasetHeader(folder, bench_rig.rig, bench_rig.backgrounds);
}

FrameSetPlayer::FrameSetPlayer(BenchRig& bench_rig, const std::string& lcm_url)
    : rig_(bench_rig),
      bus_(lcm_url),
      image_buses_(bus_, bench_rig.rig.cameras.size()),
      camera_seq_(bench_rig.rig.cameras.size(), 0) {
  for (const Camera& camera : rig_.rig.cameras) channels_.push_back(channels::Image(camera.name));
}

int64_t FrameSetPlayer::Publish(int64_t trigger_seq) {
  std::vector<image_t>& set =
      rig_.frame_sets[static_cast<size_t>(trigger_seq) % rig_.frame_sets.size()];
  const int64_t trigger = NowUtime();
  for (size_t k = 0; k < set.size(); ++k) {
    image_t& image = set[k];
    image.header.seq = camera_seq_[k]++;
    image.trigger_seq = trigger_seq;
    image.trigger_utime = trigger;
    image.host_utime = trigger;  // an instant camera: the image is there at the trigger
    image.stage_times[0].duration_us = 0;
    image.stage_times[0].end_utime = trigger;
    image.header.utime = NowUtime();
    if (!image_buses_.ForCamera(k).Publish(channels_[k], image)) return -1;
  }
  return trigger;
}

}  // namespace shapesense::bench
