#pragma once

// The capture service: serves the cameras of one process on LCM.
//
// A trigger thread triggers every software-triggered camera together at
// trigger_rate_hz (one trigger_seq and trigger_utime per frame-set); a grab
// thread per camera publishes each complete image on channels::Image(name).
// A camera that fails to open or is lost is logged, counted and retried every
// reconnect_interval_s while the others keep running. Simulated cameras also
// get their frame-set's ground truth published on channels::kTruth. Status
// ("capture") at 1 Hz: received = frames grabbed, published = images
// published, dropped = incomplete buffers plus frame-sets a camera missed
// (down, or too far behind), errors = camera failures, last_error names the
// camera.

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <string>

#include "runtime/lcm/lcm_bus.h"
#include "services/capture/camera_backend.h"
#include "services/capture/camera_factory.h"
#include "services/capture/capture_options.h"

namespace shapesense {

struct CaptureServiceArgs {
  CaptureServiceOptions options;  // as LoadCaptureOptions gives them
  std::string lcm_url;            // empty: LCM_DEFAULT_URL or LCM's default
  double duration_s = 0.0;        // > 0: stop by itself after this long
  // Log lines (camera lost, back, ...); default: standard error.
  std::function<void(const std::string&)> log;
  // Makes each camera's backend; default: MakeCameraBackend with the
  // process's simulated world. Tests put fakes here.
  std::function<std::unique_ptr<CameraBackend>(const CameraConfig&, const BackendContext&)>
      make_backend;
};

struct CameraSummary {
  int64_t published = 0;
  int64_t outages = 0;          // times it failed to open or was lost
  int64_t missed_triggers = 0;  // frame-sets it was not triggered for (down, busy or blocked)
  CameraStats stats;            // the backend's counters at the end
};

struct CaptureSummary {
  int64_t triggers = 0;  // frame-sets triggered
  std::map<std::string, CameraSummary> cameras;
};

// Runs until `stop` (or duration_s). Throws InputError (bad options: nothing
// was opened) or std::runtime_error when LCM cannot start.
CaptureSummary RunCaptureService(const CaptureServiceArgs& args, const std::atomic<bool>& stop);
// Publishes on `bus` (in-process tests over memq://).
CaptureSummary RunCaptureService(const CaptureServiceArgs& args, const std::atomic<bool>& stop,
                                 LcmBus& bus);

// The simulated world of a run when any camera is simulated (null otherwise):
// options.rig (empty: the synthetic rig) and options.simulation (its
// trajectory_file when given), t = 0 at `origin_utime`. InputError naming
// the file on an unreadable or invalid rig or trajectory file.
std::shared_ptr<const SimulatedWorld> MakeSimulatedWorld(const CaptureServiceOptions& options,
                                                         int64_t origin_utime);

}  // namespace shapesense
