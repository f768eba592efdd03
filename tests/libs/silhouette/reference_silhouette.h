#pragma once

// The silhouette rule stated step by step with OpenCV, pixel by pixel where
// OpenCV has no step: the reference the fast extractor must equal.

#include <algorithm>
#include <climits>
#include <cmath>
#include <numbers>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "libs/silhouette/silhouette.h"

namespace shapesense::testing {

// The rule stated with OpenCV's labelling: keep the largest 8-connected
// component (the one whose first pixel comes first in raster order on a tie)
// and every other of at least min_area pixels.
inline cv::Mat ReferenceKept(const cv::Mat& mask, int min_area) {
  cv::Mat labels, stats, centroids;
  const int count = cv::connectedComponentsWithStats(mask, labels, stats, centroids, 8, CV_32S);
  std::vector<int> first(count, INT_MAX);
  for (int y = 0; y < mask.rows; ++y) {
    for (int x = 0; x < mask.cols; ++x) {
      const int label = labels.at<int>(y, x);
      first[label] = std::min(first[label], y * mask.cols + x);
    }
  }
  int largest = 0;
  for (int label = 1; label < count; ++label) {
    const int area = stats.at<int>(label, cv::CC_STAT_AREA);
    const int best = largest == 0 ? -1 : stats.at<int>(largest, cv::CC_STAT_AREA);
    if (area > best || (area == best && first[label] < first[largest])) largest = label;
  }
  cv::Mat kept = cv::Mat::zeros(mask.size(), CV_8U);
  for (int label = 1; label < count; ++label) {
    if (label == largest || stats.at<int>(label, cv::CC_STAT_AREA) >= min_area) {
      kept.setTo(255, labels == label);
    }
  }
  return kept;
}

// Shadows scale the backdrop: within the angle, not brighter, not darker
// than the darkest allowed (exact, in double).
inline bool ReferenceIsShadow(const cv::Vec3b& pixel, const cv::Vec3b& background,
                              const SilhouetteOptions& options) {
  const cv::Vec3d a(pixel[0], pixel[1], pixel[2]);
  const cv::Vec3d b(background[0], background[1], background[2]);
  const double norm_a = cv::norm(a);
  const double norm_b = cv::norm(b);
  if (norm_a == 0.0 || norm_b == 0.0) return false;
  const double angle = std::acos(std::clamp(a.dot(b) / (norm_a * norm_b), -1.0, 1.0));
  return angle <= options.shadow_max_angle_deg * std::numbers::pi / 180.0 && norm_a <= norm_b &&
         norm_a >= options.shadow_min_brightness_ratio * norm_b;
}

// Whether a pixel lies so near the shadow test's limits (angle within 1e-3°,
// brightness ratio within 1e-6) that rounding may decide it either way.
inline bool NearShadowLimit(const cv::Vec3b& pixel, const cv::Vec3b& background,
                            const SilhouetteOptions& options) {
  const cv::Vec3d a(pixel[0], pixel[1], pixel[2]);
  const cv::Vec3d b(background[0], background[1], background[2]);
  const double norm_a = cv::norm(a);
  const double norm_b = cv::norm(b);
  if (norm_a == 0.0 || norm_b == 0.0) return false;
  const double angle_deg =
      std::acos(std::clamp(a.dot(b) / (norm_a * norm_b), -1.0, 1.0)) * 180.0 / std::numbers::pi;
  return std::abs(angle_deg - options.shadow_max_angle_deg) < 1e-3 ||
         std::abs(norm_a / norm_b - options.shadow_min_brightness_ratio) < 1e-6;
}

// The tape colour rule in floating point: the textbook HSV of the pixel
// against the hue range (wrapping through 0 when from > to) and the minima.
inline bool ReferenceIsTape(const cv::Vec3b& pixel, const TapeColour& tape) {
  const double b = pixel[0], g = pixel[1], r = pixel[2];
  const double high = std::max({b, g, r});
  const double chroma = high - std::min({b, g, r});
  if (chroma == 0.0 || high < tape.min_value || chroma / high < tape.min_saturation) return false;
  double hue = 0.0;
  if (high == r) {
    hue = 60.0 * (g - b) / chroma;
  } else if (high == g) {
    hue = 60.0 * (b - r) / chroma + 120.0;
  } else {
    hue = 60.0 * (r - g) / chroma + 240.0;
  }
  if (hue < 0.0) hue += 360.0;
  const double from = tape.hue_deg[0];
  const double to = tape.hue_deg[1];
  return from < to ? hue >= from && hue <= to : hue >= from || hue <= to;
}

// Threshold of |g - g_bg|, shadow test on the pixels over it, grey-scale
// closing by the square, components, labels.
inline void ReferenceSilhouette(const cv::Mat& image, const cv::Mat& background,
                                const SilhouetteOptions& options, cv::Mat* mask, cv::Mat* labels) {
  std::vector<cv::Mat> channels, background_channels;
  cv::split(image, channels);
  cv::split(background, background_channels);
  cv::Mat difference;
  cv::absdiff(channels[1], background_channels[1], difference);
  cv::Mat candidates = difference > options.threshold;
  for (int y = 0; y < image.rows && options.shadow_max_angle_deg > 0.0; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      if (candidates.at<uint8_t>(y, x) != 0 &&
          ReferenceIsShadow(image.at<cv::Vec3b>(y, x), background.at<cv::Vec3b>(y, x), options)) {
        candidates.at<uint8_t>(y, x) = 0;
      }
    }
  }
  const int r = options.dilation_radius;
  const cv::Mat square = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * r + 1, 2 * r + 1));
  cv::dilate(candidates, candidates, square);
  if (options.erode_after_dilation) cv::erode(candidates, candidates, square);
  *mask = ReferenceKept(candidates, options.min_component_area);
  *labels = cv::Mat::zeros(image.size(), CV_8U);
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      if (mask->at<uint8_t>(y, x) == 0) continue;
      const bool tape = ReferenceIsTape(image.at<cv::Vec3b>(y, x), options.tape);
      labels->at<uint8_t>(y, x) = tape ? kLabelMarker : kLabelBody;
    }
  }
}

}  // namespace shapesense::testing
