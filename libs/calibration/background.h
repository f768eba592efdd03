#pragma once

// A camera's background image: the per-pixel median of N frames of the empty
// scene, which removes what passes through a few of them (a hand, a shadow,
// noise) as long as it covers each pixel in fewer than half the frames.

#include <opencv2/core.hpp>
#include <vector>

#include "libs/calibration/calibration_board.h"

namespace shapesense {

// The median of each pixel and channel over `frames` (8-bit, all of one size
// and type); with an even count, the mean of the two middle values rounded
// up. Throws std::invalid_argument on no frames or frames that differ in
// size or type (callers check their files first and name the bad one).
cv::Mat MedianImage(const std::vector<cv::Mat>& frames, const CalibrationProgress& progress = {});

}  // namespace shapesense
