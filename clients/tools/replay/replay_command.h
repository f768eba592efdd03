#pragma once

// `shapesense replay LOG...`: carving and shape estimation on recorded LCM
// logs of camera images, as fast as the machine allows. Each camera's images
// travel on their own port (runtime/lcm/image_buses.h), so a rig's recording
// is one log per port; replay merges the logs by receive time. The images go through
// the same validation, frame-set assembly (with the log's receive times as
// the clock) and the same CarvingStage and ShapeStage as in the live
// services, so a frame-set gives the shape the live pipeline gave.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <ostream>
#include <vector>

#include "shapesense/shape_t.hpp"

namespace shapesense {

struct ReplayArgs {
  // LCM logs with image_t on the camera channels (one per camera's port, or
  // one with all), merged by their events' times.
  std::vector<std::filesystem::path> logs;
  std::filesystem::path out;      // JSON lines as the offline command writes (may be empty)
  std::filesystem::path out_log;  // LCM log of shape_t on the shape channel (may be empty)
  std::filesystem::path
      config;  // the carving service's config (rig, backgrounds, silhouette, carving, assembly)
  std::filesystem::path shape_config;  // the shape service's config (silhouette, shape, q)
  std::filesystem::path rig;           // override both configs'
  std::filesystem::path backgrounds;
  bool progress = true;  // progress bar on a terminal
};

struct ReplaySummary {
  int64_t events = 0;               // in the log
  int64_t images = 0;               // image messages on the camera channels
  int64_t rejected = 0;             // malformed, unknown camera, duplicate or late images
  int64_t frame_sets = 0;           // complete frame-sets
  int64_t dropped_sets = 0;         // incomplete frame-sets (timed out or evicted)
  int64_t not_carved = 0;           // complete sets whose images could not be decoded
  int64_t measured = 0;             // valid shapes
  double mean_silhouette_ms = 0.0;  // per frame-set, over the measured ones
  double mean_carving_ms = 0.0;
  double mean_shape_ms = 0.0;
};

// Called with every shape as written (for tests and tools).
using ReplayObserver = std::function<void(const shape_t& shape)>;

// Throws InputError (before writing anything) on no log, a missing or
// unreadable one, a bad config, rig or backgrounds, or no output given.
ReplaySummary RunReplay(const ReplayArgs& args, std::ostream& log,
                        const ReplayObserver& observer = {});

// Registers `shapesense replay`.
void AddReplayCommand(CLI::App& app);

}  // namespace shapesense
