#pragma once

#include <optional>
#include <string>
#include <vector>

#include "services/capture/camera_backend.h"
#include "services/capture/preview_publisher.h"
#include "services/capture/simulated_world.h"

namespace shapesense {

// `shapesense-capture background`: the median of `frames` frames per camera.
struct BackgroundOptions {
  int frames = 25;
  std::string out = "background";

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("frames", frames, "frames per camera whose per-pixel median is the background (1-1000)");
    visit("out", out,
          "folder of the backgrounds, one <camera>.png each (the dataset's background/)");
  }
  std::string Validate() const;
};

// The capture service (config/capture.yaml).
struct CaptureServiceOptions {
  std::vector<CameraConfig> cameras;
  // Software trigger: every software-triggered camera of this process is
  // triggered together at this rate, with one trigger sequence.
  double trigger_rate_hz = 30.0;
  // Rig file of the simulated cameras; empty: the synthetic rig (cam0-cam2).
  std::string rig;
  // How images are published: none (raw rows) or png (lossless, smaller, slower).
  std::string compression = "none";
  int png_level = 1;
  // A camera that failed to open or was lost is retried this often, s.
  double reconnect_interval_s = 1.0;
  // Simulated cameras: publish the ground truth of each frame-set on SHAPESENSE_TRUTH.
  bool publish_truth = true;
  SimulationOptions simulation;
  BackgroundOptions background;
  PreviewOptions preview;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("cameras", cameras, "the cameras this process serves (see CameraConfig)");
    visit("trigger_rate_hz", trigger_rate_hz, "software trigger rate, Hz (0.1-1000)");
    visit("rig", rig, "rig file of simulated cameras (empty: the synthetic rig cam0-cam2)");
    visit("compression", compression, "image compression: none | png");
    visit("png_level", png_level, "PNG compression level (0-9)");
    visit("reconnect_interval_s", reconnect_interval_s,
          "retry period of a camera that is down, s (0.05-60)");
    visit("publish_truth", publish_truth, "simulated cameras: publish the ground truth");
    visit("simulation", simulation, "the simulated manipulator's trajectory and rendering");
    visit("background", background, "the background command");
    visit("preview", preview,
          "small JPEGs of each camera for the web monitor, on SHAPESENSE_PREVIEW_<camera>");
  }
  // Also checks every camera (keys named cameras[i].key) and unique names;
  // an empty camera list is valid here (cameras may come from --camera).
  std::string Validate() const;
};

// The options of a run: the config file (empty: defaults), then each
// `--camera NAME=BACKEND:DEVICE` (a new name adds a camera; a configured name
// takes the new backend and device, keeping its other keys), then `rate` when
// given. Throws InputError naming the file or the flag and the key, and when
// no camera is left.
CaptureServiceOptions LoadCaptureOptions(const std::string& config_path,
                                         const std::vector<std::string>& camera_specs,
                                         std::optional<double> rate_hz = std::nullopt);

}  // namespace shapesense
