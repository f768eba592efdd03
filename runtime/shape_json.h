#pragma once

#include <nlohmann/json.hpp>
#include <string>

#include "runtime/sensing_pipeline.h"

namespace shapesense {

// One line of the offline command's output (docs/dataset.md): frame, valid,
// centerline, markers, tip, arc_length, curvature, ... and the stage times.
// Coordinates are rounded to 0.1 µm to keep lines short.
nlohmann::json ShapeToJson(const std::string& frame, const ShapeEstimate& shape,
                           const StageTimes& times, double load_ms);

// The line of a frame that could not be measured at all (e.g. an unreadable image).
nlohmann::json FrameErrorToJson(const std::string& frame, const std::string& error);

}  // namespace shapesense
