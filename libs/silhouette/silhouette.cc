#include "libs/silhouette/silhouette.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstring>
#include <numbers>
#include <opencv2/core/check.hpp>
#include <stdexcept>

#include "libs/core/error.h"
#include "libs/silhouette/green_difference.h"

namespace shapesense {
namespace {

std::string DescribeImage(const cv::Mat& image) {
  if (image.empty()) return "an empty image";
  return std::to_string(image.cols) + "x" + std::to_string(image.rows) + " " +
         cv::typeToString(image.type());
}

void CheckInputs(const cv::Mat& image, const cv::Mat& background, const Silhouette* out) {
  const std::string where = "SilhouetteExtractor::Extract: ";
  if (out == nullptr) throw std::invalid_argument(where + "no output Silhouette given");
  if (image.empty() || image.type() != CV_8UC3) {
    throw std::invalid_argument(where + "image: expected 8-bit BGR (CV_8UC3), got " +
                                DescribeImage(image));
  }
  if (background.empty() || background.type() != CV_8UC3) {
    throw std::invalid_argument(where + "background: expected 8-bit BGR (CV_8UC3), got " +
                                DescribeImage(background));
  }
  if (image.size() != background.size()) {
    throw std::invalid_argument(where + "background size " + DescribeImage(background) +
                                " differs from image size " + DescribeImage(image));
  }
}

const SilhouetteOptions& Checked(const SilhouetteOptions& options) {
  if (const std::string error = options.Validate(); !error.empty()) {
    throw std::invalid_argument("SilhouetteOptions: " + error);
  }
  return options;
}

}  // namespace

std::string SilhouetteOptions::Validate() const {
  if (threshold < 1 || threshold > 254) return Expected("threshold", "1-254", threshold);
  if (dilation_radius < 0 || dilation_radius > 10) {
    return Expected("dilation_radius", "0-10", dilation_radius);
  }
  if (!(shadow_max_angle_deg >= 0.0 && shadow_max_angle_deg < 90.0)) {
    return Expected("shadow_max_angle_deg", "0 (off) or an angle below 90", shadow_max_angle_deg);
  }
  if (!(shadow_min_brightness_ratio >= 0.0 && shadow_min_brightness_ratio <= 1.0)) {
    return Expected("shadow_min_brightness_ratio", "0-1", shadow_min_brightness_ratio);
  }
  if (min_component_area < 0) {
    return Expected("min_component_area", "0 or more", min_component_area);
  }
  if (const std::string error = tape.Validate(); !error.empty()) return "tape." + error;
  return {};
}

SilhouetteExtractor::SilhouetteExtractor(const SilhouetteOptions& options)
    : options_(Checked(options)), tape_(options.tape) {
  const double cosine = std::cos(options.shadow_max_angle_deg * std::numbers::pi / 180.0);
  const double scale = static_cast<double>(int64_t{1} << kShadowFixedBits);
  shadow_cos2_fixed_ = std::llround(cosine * cosine * scale);
  shadow_min_brightness2_fixed_ = std::llround(options.shadow_min_brightness_ratio *
                                               options.shadow_min_brightness_ratio * scale);
}

void SilhouetteExtractor::Extract(const cv::Mat& image, const cv::Mat& background,
                                  Silhouette* out) const {
  CheckInputs(image, background, out);
  const int width = image.cols;
  const int height = image.rows;
  const bool test_shadows = options_.shadow_max_angle_deg > 0.0;
  out->difference.create(image.size(), CV_8U);
  SilhouetteScratch& scratch = out->scratch;
  scratch.candidates.Resize(width, height);  // every word is written below
  for (int y = 0; y < height; ++y) {
    const uint8_t* image_row = image.ptr<uint8_t>(y);
    const uint8_t* background_row = background.ptr<uint8_t>(y);
    uint64_t* candidates = scratch.candidates.Row(y);
    const bool any = GreenDifferenceRow(image_row, background_row, width, options_.threshold,
                                        out->difference.ptr<uint8_t>(y), candidates);
    if (any && test_shadows) {
      RejectShadows(image_row, background_row, candidates, scratch.candidates.words_per_row());
    }
  }
  Close(&scratch);
  ExtractRuns(scratch.closed, &scratch.runs);
  KeepManipulatorComponents(scratch.runs, options_.min_component_area, &scratch.components,
                            &out->runs);
  Paint(image, out);
}

// Shadows on the backdrop only scale its colour: same direction in RGB, not
// brighter, and not darker than the darkest shadow. Integer and branch-free:
// shadow and tube pixels interleave along the tube's edge, where branches
// would mispredict; the cosine and brightness bounds are fixed point.
bool SilhouetteExtractor::IsShadow(const uint8_t* pixel, const uint8_t* background) const {
  const int b = pixel[0], g = pixel[1], r = pixel[2];
  const int bb = background[0], bg = background[1], br = background[2];
  const int64_t dot = b * bb + g * bg + r * br;
  const int64_t norm2 = b * b + g * g + r * r;
  const int64_t background_norm2 = bb * bb + bg * bg + br * br;
  const bool same_direction =
      dot > 0 && (dot * dot << kShadowFixedBits) >= shadow_cos2_fixed_ * norm2 * background_norm2;
  const bool not_brighter = norm2 <= background_norm2;
  const bool not_too_dark =
      (norm2 << kShadowFixedBits) >= shadow_min_brightness2_fixed_ * background_norm2;
  return same_direction & not_brighter & not_too_dark;
}

void SilhouetteExtractor::RejectShadows(const uint8_t* image_row, const uint8_t* background_row,
                                        uint64_t* candidates, int words) const {
  for (int i = 0; i < words; ++i) {
    uint64_t shadows = 0;  // in a register: no store-to-load chain through candidates[i]
    for (uint64_t left = candidates[i]; left != 0; left &= left - 1) {
      const int bit = std::countr_zero(left);
      const ptrdiff_t at = ptrdiff_t{3} * (64 * i + bit);  // BGR bytes into the rows
      shadows |= static_cast<uint64_t>(IsShadow(image_row + at, background_row + at)) << bit;
    }
    candidates[i] &= ~shadows;
  }
}

void SilhouetteExtractor::Close(SilhouetteScratch* scratch) const {
  if (!options_.erode_after_dilation) {
    DilateSquare(scratch->candidates, options_.dilation_radius, &scratch->pass, &scratch->closed);
    return;
  }
  DilateSquare(scratch->candidates, options_.dilation_radius, &scratch->pass, &scratch->dilated);
  ErodeSquare(scratch->dilated, options_.dilation_radius, &scratch->pass, &scratch->closed);
}

void SilhouetteExtractor::Paint(const cv::Mat& image, Silhouette* out) const {
  out->mask.create(image.size(), CV_8U);
  out->labels.create(image.size(), CV_8U);
  out->mask.setTo(0);
  out->labels.setTo(kLabelNone);
  int x_min = image.cols, y_min = image.rows, x_max = -1, y_max = -1;
  out->area = 0;
  for (const RowRun& run : out->runs) {
    std::memset(out->mask.ptr<uint8_t>(run.y) + run.x0, 255, run.x1 - run.x0);
    const uint8_t* pixel = image.ptr<uint8_t>(run.y) + ptrdiff_t{3} * run.x0;
    uint8_t* label = out->labels.ptr<uint8_t>(run.y);
    for (int x = run.x0; x < run.x1; ++x, pixel += 3) {
      label[x] = tape_.IsTape(pixel) ? kLabelMarker : kLabelBody;
    }
    x_min = std::min(x_min, run.x0);
    x_max = std::max(x_max, run.x1 - 1);
    y_min = std::min(y_min, run.y);
    y_max = std::max(y_max, run.y);
    out->area += run.x1 - run.x0;
  }
  out->bounds =
      out->area > 0 ? cv::Rect(x_min, y_min, x_max - x_min + 1, y_max - y_min + 1) : cv::Rect();
}

}  // namespace shapesense
