#pragma once

// The tape's colour learnt from a calibration image: one picture of the
// manipulator with its tape in view, and the same camera's background.
//
// The silhouette's pixels that the configured tape colour (the prior
// window) labels tape, away from the outline (there the tape mixes with the
// backdrop: red over green turns yellow), are histogrammed by hue; the
// dominant peak and the bins around it down to 2 % of its height are the
// tape's cluster. The learnt hue range is the peak ± 1.5 × the cluster's
// 1st and 99th percentile distance from it, at least ± 10°, rounded out to
// whole degrees; the saturation and value minima are 0.8 × the cluster's 1st
// percentiles (the calibration image shows the tape under one light; the
// margin keeps it when darker or paler).

#include <cstdint>
#include <opencv2/core.hpp>

#include "libs/silhouette/silhouette.h"
#include "libs/silhouette/tape_classifier.h"

namespace shapesense {

// Fewest cluster pixels to learn from: fewer give no percentiles worth the name.
inline constexpr int64_t kMinTapeColourPixels = 50;

struct LearntTapeColour {
  TapeColour colour;          // the learnt hue range and minima
  double peak_hue_deg = 0.0;  // the cluster's centre (its median hue)
  int64_t pixels = 0;         // pixels of the cluster, learnt from
  int64_t labelled = 0;       // silhouette pixels the learnt colour labels tape
  int64_t silhouette = 0;     // silhouette pixels
};

// Learns the tape's colour from `image` and `background` (8-bit BGR of one
// size), with options.tape as the prior window. Throws InputError when
// there is no silhouette, when the prior window matches no pixel of it, or
// when the tape's cluster holds fewer than kMinTapeColourPixels;
// std::invalid_argument on images of another type or size, or options that
// fail Validate(). No I/O.
LearntTapeColour LearnTapeColour(const cv::Mat& image, const cv::Mat& background,
                                 const SilhouetteOptions& options);

}  // namespace shapesense
