#include "services/capture/background_capture.h"

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <thread>

#include "libs/calibration/background.h"
#include "libs/core/error.h"
#include "runtime/file_io.h"
#include "runtime/lcm/lcm_bus.h"
#include "services/capture/capture_service.h"

namespace shapesense {
namespace {

using Clock = std::chrono::steady_clock;
constexpr auto kFrameTimeout = std::chrono::seconds(5);

// Waits for the next frame, at most kFrameTimeout, in short grabs so that a stop is seen.
cv::Mat NextFrame(CameraBackend& camera, const std::atomic<bool>& stop) {
  const Clock::time_point deadline = Clock::now() + kFrameTimeout;
  CameraFrame frame;
  while (!stop && Clock::now() < deadline) {
    if (camera.Grab(std::chrono::milliseconds(100), &frame)) return frame.image;
  }
  if (stop) throw std::runtime_error("background: stopped before the end");
  throw CameraError(camera.name() + ": no frame for 5 s");
}

std::vector<cv::Mat> GrabFrames(CameraBackend& camera, const CameraConfig& config, int count,
                                double trigger_rate_hz, const std::atomic<bool>& stop) {
  const auto period = std::chrono::duration_cast<Clock::duration>(
      std::chrono::duration<double>(1.0 / trigger_rate_hz));
  std::vector<cv::Mat> frames;
  Clock::time_point next = Clock::now();
  for (int i = 0; i < count; ++i) {
    if (config.Trigger() == TriggerMode::kSoftware) {
      std::this_thread::sleep_until(next);
      next += period;
      camera.Trigger(i, NowUtime());
    }
    frames.push_back(NextFrame(camera, stop));
  }
  return frames;
}

}  // namespace

std::vector<std::filesystem::path> RunBackgroundCapture(const BackgroundCaptureArgs& args,
                                                        const std::atomic<bool>& stop) {
  CaptureServiceOptions options = args.options;
  if (const std::string error = options.Validate(); !error.empty()) throw InputError(error);
  options.simulation.show_manipulator = false;
  const auto log = args.log ? args.log : [](const std::string& line) {
    std::fprintf(stderr, "[background] %s\n", line.c_str());
  };
  const BackendContext context{MakeSimulatedWorld(options, NowUtime())};
  std::vector<std::filesystem::path> written;
  for (const CameraConfig& config : options.cameras) {
    std::unique_ptr<CameraBackend> camera =
        args.make_backend ? args.make_backend(config, context) : MakeCameraBackend(config, context);
    camera->Open();
    const std::vector<cv::Mat> frames =
        GrabFrames(*camera, config, options.background.frames, options.trigger_rate_hz, stop);
    camera->Close();
    const std::filesystem::path path =
        std::filesystem::path(options.background.out) / (config.name + ".png");
    std::filesystem::create_directories(path.parent_path());
    WritePng(path, MedianImage(frames));
    log(config.name + ": median of " + std::to_string(frames.size()) + " frames -> " +
        path.string());
    written.push_back(path);
  }
  return written;
}

}  // namespace shapesense
