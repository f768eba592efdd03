#pragma once

// The picture `shapesense estimate` writes: the sensed distal shapes against
// the model's, front (x-y) and side (z-y) views of the base frame, every
// pose's distal section drawn from a common start.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/mechanics/stiffness_estimation.h"

namespace shapesense {

struct ShapePlotOptions {
  int panel_size = 560;  // pixels, each of the two square views
  std::string model_label = "model";
};

// BGR, 8 bits, two panels side by side.
cv::Mat PlotSensedAgainstModel(const TendonModel& model, const std::vector<PoseSample>& poses,
                               const ShapePlotOptions& options);

}  // namespace shapesense
