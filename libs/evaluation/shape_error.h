#pragma once

#include <vector>

#include "libs/centerline/shape_estimator.h"
#include "libs/sim/tube_scene.h"

namespace shapesense {

// How far a measured shape is from the ground truth, mm.
struct ShapeError {
  double centerline_rms = 0.0;  // each measured point to the true centreline
  double centerline_max = 0.0;
  double coverage_rms = 0.0;  // each true point to the measured centreline (a short
                              // or truncated estimate cannot look good)
  double tip = 0.0;
  double length = 0.0;      // |measured − true length|
  double marker_rms = 0.0;  // each true marker to the nearest measured one
  double marker_max = 0.0;
  int markers_expected = 0;
  int markers_found = 0;
};

// Requires a valid estimate.
ShapeError CompareShape(const ShapeEstimate& estimate, const GroundTruth& truth);

// Mean and maximum of each figure over many frames.
struct ShapeErrorSummary {
  int frames = 0;
  int failed = 0;  // invalid estimates, not in the figures
  ShapeError mean;
  ShapeError max;
};

ShapeErrorSummary Summarize(const std::vector<ShapeError>& errors, int failed);

}  // namespace shapesense
