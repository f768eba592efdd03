#pragma once

#include <algorithm>
#include <cstdint>
#include <limits>

namespace shapesense::carving_detail {

// A rectangle of pixels, bounds inclusive; empty when x0 > x1. int16 keeps
// the hierarchy's bounds compact (images up to 32767 px a side).
struct PixelRect {
  int16_t x0 = std::numeric_limits<int16_t>::max();
  int16_t y0 = std::numeric_limits<int16_t>::max();
  int16_t x1 = std::numeric_limits<int16_t>::min();
  int16_t y1 = std::numeric_limits<int16_t>::min();

  bool Empty() const { return x0 > x1; }
  // Pixels in a non-empty rectangle.
  int32_t Area() const { return (int32_t{x1} - x0 + 1) * (int32_t{y1} - y0 + 1); }

  void Include(int x, int y) {
    x0 = std::min(x0, static_cast<int16_t>(x));
    y0 = std::min(y0, static_cast<int16_t>(y));
    x1 = std::max(x1, static_cast<int16_t>(x));
    y1 = std::max(y1, static_cast<int16_t>(y));
  }
  void Include(const PixelRect& other) {
    x0 = std::min(x0, other.x0);
    y0 = std::min(y0, other.y0);
    x1 = std::max(x1, other.x1);
    y1 = std::max(y1, other.y1);
  }
};

}  // namespace shapesense::carving_detail
