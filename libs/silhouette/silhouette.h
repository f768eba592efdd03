#pragma once

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "libs/silhouette/bit_mask.h"
#include "libs/silhouette/run_components.h"
#include "libs/silhouette/tape_classifier.h"

namespace shapesense {

// Label values in Silhouette::labels.
inline constexpr uint8_t kLabelNone = 0;
inline constexpr uint8_t kLabelBody = 1;
inline constexpr uint8_t kLabelMarker = 2;  // tape

struct SilhouetteOptions {
  // A pixel is foreground when |green - green_background| exceeds this, grey levels.
  int threshold = 30;
  // Grey-scale dilation of the difference image before the threshold, to fill
  // small holes, px (0: none); the element is the (2r+1)² square.
  int dilation_radius = 1;
  // Erode by the same radius after the threshold so the dilation does not
  // grow the silhouette (a closing); the reference only dilates.
  bool erode_after_dilation = true;
  // Shadow test: a foreground pixel whose RGB vector lies within this angle
  // of the background's and is darker is a shadow, degrees (0: test off).
  double shadow_max_angle_deg = 6.0;
  // ... and whose brightness is at least this fraction of the background's.
  double shadow_min_brightness_ratio = 0.3;
  // Connected components smaller than this (8-connected), px, are dropped;
  // the largest component is always kept.
  int min_component_area = 200;
  // Mask pixels of this colour are tape (kLabelMarker), the others body.
  TapeColour tape;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("threshold", threshold, "green-difference threshold, grey levels (1-254)");
    visit("dilation_radius", dilation_radius, "grey-scale dilation before thresholding, px (0-10)");
    visit("erode_after_dilation", erode_after_dilation, "erode back after dilating (a closing)");
    visit("shadow_max_angle_deg", shadow_max_angle_deg, "RGB-angle shadow test, degrees (0: off)");
    visit("shadow_min_brightness_ratio", shadow_min_brightness_ratio,
          "darkest shadow, fraction of background brightness (0-1)");
    visit("min_component_area", min_component_area, "smallest connected component kept, px");
    visit("tape", tape, "tape colour (HSV): mask pixels of it are tape, the others body");
  }
  std::string Validate() const;
};

// Working memory of SilhouetteExtractor::Extract, kept with its output so
// that repeated calls allocate nothing and extractions into different
// Silhouettes can run on different threads. Not part of the result.
struct SilhouetteScratch {
  BitMask candidates;  // over the threshold and not shadow
  BitMask dilated;
  BitMask closed;
  BitMask pass;  // the horizontal pass of the morphology
  RunImage runs;
  ComponentScratch components;
};

// The silhouette of the manipulator in one camera image. All images have the
// size of the input; the buffers are reused between calls.
struct Silhouette {
  cv::Mat mask;        // CV_8U: 255 manipulator, 0 background
  cv::Mat labels;      // CV_8U: kLabelNone outside the mask, kLabelBody or kLabelMarker inside
  cv::Mat difference;  // CV_8U: |green - green_background| before dilation, for sub-pixel edges
  cv::Rect bounds;     // bounding box of the mask; empty when the mask is empty
  int64_t area = 0;    // pixels in the mask
  // The mask as runs [x0, x1) of rows, in raster order, so later stages can
  // walk the foreground without scanning the image. Filled by Extract; a
  // Silhouette built by hand may leave it empty.
  std::vector<RowRun> runs;

  SilhouetteScratch scratch;
};

// Silhouette extraction after the reference method: green-channel difference
// to a background image, grey-scale dilation, threshold, shadow rejection,
// connected components keeping the manipulator, tape labelled by its colour.
//
// How it is computed (same result as the steps above, at a fraction of the
// cost: about 0.11 ms for a 640×480 frame on one core, 0.08 ms without the
// shadow test):
//  - one vectorised pass (AVX2 where the CPU has it, else OpenCV's baseline
//    SIMD) writes `difference` and a bitmap (1 bit per pixel) of the pixels
//    over the threshold; nothing later reads the whole image again. Grey-scale dilation by a flat
//    element then a threshold equals the threshold then a binary dilation, so the dilation works on
//    the bitmap. The structuring element is the (2r+1)² square (r = dilation_radius), as cv::dilate
//    with a rectangle.
//  - the shadow test runs on the pixels over the threshold, before the
//    closing: a hole in the tube looks like the backdrop, so testing it after
//    the dilation filled it would call it a shadow and open it again.
//  - closing on the bitmap (the border counts as background for the dilation
//    and as foreground for the erosion, so a tube leaving the image keeps its
//    end), then runs, union-find components, and the labels only on the kept
//    runs, by TapeClassifier's two lookups (about 2 ns a mask pixel, 2.5 on
//    tape; the construction builds its tables in about 1 ms).
class SilhouetteExtractor {
 public:
  // Throws std::invalid_argument when the options fail Validate().
  explicit SilhouetteExtractor(const SilhouetteOptions& options);

  // `image` and `background`: 8-bit BGR of the same size. Throws
  // std::invalid_argument on a size or type mismatch. Const and free of shared
  // state: several threads may extract at once into different Silhouettes.
  void Extract(const cv::Mat& image, const cv::Mat& background, Silhouette* out) const;

  const SilhouetteOptions& options() const { return options_; }

 private:
  bool IsShadow(const uint8_t* pixel, const uint8_t* background) const;
  void RejectShadows(const uint8_t* image_row, const uint8_t* background_row, uint64_t* candidates,
                     int words) const;
  void Close(SilhouetteScratch* scratch) const;
  void Paint(const cv::Mat& image, Silhouette* out) const;

  SilhouetteOptions options_;
  // cos² of the largest shadow angle and the squared brightness ratio, fixed
  // point: dot² and |a|²|b|² reach 3.8e10, so 20 fractional bits fit in 64.
  static constexpr int kShadowFixedBits = 20;
  int64_t shadow_cos2_fixed_ = 0;
  int64_t shadow_min_brightness2_fixed_ = 0;
  TapeClassifier tape_;
};

}  // namespace shapesense
