#pragma once

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>

#include "libs/carving/pixel_rect.h"

namespace shapesense::carving_detail {

// Counts the nonzero pixels of a mask in any rectangle in O(1). The sums
// cover only the bounding box of the nonzero pixels: a thin manipulator's
// silhouette fills a small part of the image, and rebuilding the sums is part
// of every frame's cost.
class SummedAreaTable {
 public:
  // `mask`: CV_8UC1, nonzero = inside. `known_box`: the bounding box of its
  // nonzero pixels when the caller has it (Silhouette::bounds); empty, it is
  // found by scanning the mask.
  explicit SummedAreaTable(const cv::Mat& mask, const cv::Rect& known_box = {});

  // Nonzero pixels of the mask inside `rect` (any rectangle, even one
  // reaching outside the image or empty).
  int32_t Count(const PixelRect& rect) const {
    const int x0 = std::max<int>(rect.x0, box_.x) - box_.x;
    const int y0 = std::max<int>(rect.y0, box_.y) - box_.y;
    const int x1 = std::min<int>(rect.x1, box_.x + box_.width - 1) - box_.x;
    const int y1 = std::min<int>(rect.y1, box_.y + box_.height - 1) - box_.y;
    if (x0 > x1 || y0 > y1) return 0;
    const int32_t* top = sums_.get() + static_cast<ptrdiff_t>(y0) * stride_;
    const int32_t* bottom = sums_.get() + static_cast<ptrdiff_t>(y1 + 1) * stride_;
    return bottom[x1 + 1] - bottom[x0] - top[x1 + 1] + top[x0];
  }

  // Bounding box of the nonzero pixels (empty when there are none).
  const cv::Rect& box() const { return box_; }

 private:
  cv::Rect box_;
  int stride_ = 0;  // box_.width + 1
  // (box_.height + 1) × stride_: sums_[y][x] = nonzero pixels in the box's
  // first y rows and x columns.
  std::unique_ptr<int32_t[]> sums_;
};

}  // namespace shapesense::carving_detail
