#pragma once

// Camera previews for people: a few pictures a second of each camera, small
// JPEGs on SHAPESENSE_PREVIEW_<camera> (rig network, one datagram each), for
// the web monitor on any host. The pipeline's images stay on their host's
// own ports; a browser gets these instead (docs/monitor.md).
//
// Which frames: every n-th trigger sequence, the same for every camera (so
// the previews of one instant form a set the monitor can overlay with that
// frame-set's silhouettes and shape). Encoded on a thread of its own at
// SCHED_IDLE behind a drop-oldest queue, so a preview never delays an image
// of the pipeline: on a machine the pipeline fills, previews are dropped.
#include <atomic>
#include <cstdint>
#include <functional>
#include <string>
#include <thread>

#include "runtime/lcm/bounded_queue.h"
#include "services/capture/camera_backend.h"
#include "shapesense/image_t.hpp"

namespace shapesense {

struct PreviewOptions {
  double rate_hz = 10.0;  // 0: no previews
  int width = 320;        // pixels; the height keeps the aspect (never enlarged)
  int jpeg_quality = 80;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("rate_hz", rate_hz, "previews per camera per second, at most (0: none; 0-30)");
    visit("width", width, "preview width, pixels (32-1280; never larger than the image)");
    visit("jpeg_quality", jpeg_quality, "JPEG quality (10-100)");
  }
  std::string Validate() const;
};

// Every how many trigger sequences a preview is taken, at `trigger_rate_hz`
// (0: never).
int64_t PreviewEvery(const PreviewOptions& options, double trigger_rate_hz);

// The preview of one frame: downscaled, JPEG, with the frame's identity.
image_t PreviewMessage(const std::string& camera, const CameraFrame& frame,
                       const PreviewOptions& options, int64_t publish_utime);

class PreviewPublisher {
 public:
  using Publish = std::function<void(const std::string& channel, image_t& message)>;

  PreviewPublisher(const PreviewOptions& options, double trigger_rate_hz, Publish publish);
  ~PreviewPublisher();
  PreviewPublisher(const PreviewPublisher&) = delete;
  PreviewPublisher& operator=(const PreviewPublisher&) = delete;

  // From a grab thread: queues a copy of the frame when its trigger is one
  // that is previewed (a free-running frame: by its frame id).
  void Offer(const std::string& camera, const CameraFrame& frame);
  int64_t published() const { return published_.load(); }
  int64_t dropped() const { return queue_.Dropped(); }

 private:
  struct Job {
    std::string camera;
    CameraFrame frame;
  };
  void Run();

  const PreviewOptions options_;
  const int64_t every_;
  Publish publish_;
  BoundedQueue<Job> queue_;
  std::atomic<int64_t> published_{0};
  std::atomic<bool> stopping_{false};
  std::thread thread_;  // last: starts once everything above exists
};

}  // namespace shapesense
