#pragma once

// `shapesense-capture background`: each camera's background image, the
// per-pixel median of N frames of the empty scene (libs/calibration
// MedianImage), written as OUT/<camera>.png (a dataset's background/ folder).

#include <atomic>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "services/capture/camera_factory.h"
#include "services/capture/capture_options.h"

namespace shapesense {

struct BackgroundCaptureArgs {
  CaptureServiceOptions options;  // cameras, trigger rate, simulation; background.frames and .out
  std::function<void(const std::string&)> log;  // default: standard error
  // As in CaptureServiceArgs; default MakeCameraBackend.
  std::function<std::unique_ptr<CameraBackend>(const CameraConfig&, const BackendContext&)>
      make_backend;
};

// Grabs the frames of one camera after another (software-triggered cameras
// are triggered at trigger_rate_hz) and writes the medians; simulated
// cameras show the backdrop alone. Returns the files written. Throws
// CameraError when a camera cannot be opened or gives no frame for 5 s, and
// std::runtime_error when stopped before the end (nothing half-done is left:
// each file is written whole, after its camera's last frame).
std::vector<std::filesystem::path> RunBackgroundCapture(const BackgroundCaptureArgs& args,
                                                        const std::atomic<bool>& stop);

}  // namespace shapesense
