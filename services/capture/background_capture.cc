#include "services/capture/background_capture.h"

#include <chrono>
#include <cstdio>
#include <functional>
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
constexpr auto kRetriggerAfter = std::chrono::seconds(1);

// Waits for the next frame, at most kFrameTimeout, in short grabs so that a
// stop is seen. A software trigger that brought nothing within
// kRetriggerAfter is sent again (`retrigger`): a trigger can be lost, as a
// camera's first after its start can be, and every frame of a backdrop
// shows the same, so a late second answer does no harm to the median.
cv::Mat NextFrame(CameraBackend& camera, const std::function<void()>& retrigger,
                  const std::atomic<bool>& stop) {
  const Clock::time_point deadline = Clock::now() + kFrameTimeout;
  Clock::time_point next_retrigger = Clock::now() + kRetriggerAfter;
  CameraFrame frame;
  while (!stop && Clock::now() < deadline) {
    if (camera.Grab(std::chrono::milliseconds(100), &frame)) return frame.image;
    if (retrigger && Clock::now() >= next_retrigger) {
      retrigger();
      next_retrigger += kRetriggerAfter;
    }
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
  const bool software = config.Trigger() == TriggerMode::kSoftware;
  for (int i = 0; i < count; ++i) {
    const auto trigger = [&camera, i] { camera.Trigger(i, NowUtime()); };
    if (software) {
      std::this_thread::sleep_until(next);
      next += period;
      trigger();
    }
    frames.push_back(NextFrame(camera, software ? std::function<void()>(trigger) : nullptr, stop));
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
