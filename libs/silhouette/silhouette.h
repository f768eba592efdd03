#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace shapesense {

// Label values in Silhouette::labels.
inline constexpr uint8_t kLabelNone = 0;
inline constexpr uint8_t kLabelBody = 1;
inline constexpr uint8_t kLabelMarker = 2;  // red tape

struct SilhouetteOptions {
  // A pixel is foreground when |green - green_background| exceeds this, grey levels.
  int threshold = 30;
  // Grey-scale dilation of the difference image before the threshold, to fill
  // small holes, px (0: none).
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
  // Red tape: red > marker_min_red, and red > marker_red_ratio × max(green, blue).
  int marker_min_red = 90;
  double marker_red_ratio = 1.8;

  template <class Visitor>
  void VisitFields(Visitor&& visit) {
    visit("threshold", threshold, "green-difference threshold, grey levels (1-254)");
    visit("dilation_radius", dilation_radius, "grey-scale dilation before thresholding, px (0-10)");
    visit("erode_after_dilation", erode_after_dilation, "erode back after dilating (a closing)");
    visit("shadow_max_angle_deg", shadow_max_angle_deg, "RGB-angle shadow test, degrees (0: off)");
    visit("shadow_min_brightness_ratio", shadow_min_brightness_ratio, "darkest shadow, fraction of background brightness (0-1)");
    visit("min_component_area", min_component_area, "smallest connected component kept, px");
    visit("marker_min_red", marker_min_red, "red tape: minimum red level (0-255)");
    visit("marker_red_ratio", marker_red_ratio, "red tape: red over max(green, blue) (> 1)");
  }
  std::string Validate() const;
};

// The silhouette of the manipulator in one camera image. All images have the
// size of the input; the buffers are reused between calls.
struct Silhouette {
  cv::Mat mask;        // CV_8U: 255 manipulator, 0 background
  cv::Mat labels;      // CV_8U: kLabelNone outside the mask, kLabelBody or kLabelMarker inside
  cv::Mat difference;  // CV_8U: |green - green_background| before dilation, for sub-pixel edges
};

// Silhouette extraction after the reference method: green-channel difference
// to a background image, grey-scale dilation, threshold, shadow rejection,
// connected components keeping the manipulator, red tape labelled by colour.
class SilhouetteExtractor {
 public:
  explicit SilhouetteExtractor(const SilhouetteOptions& options);

  // `image` and `background`: 8-bit BGR of the same size. Throws
  // std::invalid_argument on a size or type mismatch.
  void Extract(const cv::Mat& image, const cv::Mat& background, Silhouette* out) const;

  const SilhouetteOptions& options() const { return options_; }

 private:
  SilhouetteOptions options_;
};

}  // namespace shapesense
