#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace shapesense {

// A binary image with one bit per pixel, each row padded to whole 64-bit
// words: the morphology of a 640×480 mask then touches 4800 words instead of
// 307200 bytes. Bit x % 64 of word x / 64 of a row is pixel x; the padding
// bits past the width are always 0.
class BitMask {
 public:
  // Sizes the mask and clears it; keeps the storage when it is big enough.
  void Reset(int width, int height);
  // Sizes the mask, leaving its pixels unspecified (for a caller that writes
  // every row).
  void Resize(int width, int height);

  int width() const { return width_; }
  int height() const { return height_; }
  int words_per_row() const { return words_per_row_; }

  uint64_t* Row(int y) { return bits_.data() + static_cast<std::size_t>(y) * words_per_row_; }
  const uint64_t* Row(int y) const {
    return bits_.data() + static_cast<std::size_t>(y) * words_per_row_;
  }
  bool Get(int x, int y) const { return (Row(y)[x >> 6] >> (x & 63)) & 1u; }
  void Set(int x, int y) { Row(y)[x >> 6] |= uint64_t{1} << (x & 63); }

  // Mask of the pixels of the last word of a row that are inside the image.
  uint64_t LastWordMask() const;

 private:
  int width_ = 0;
  int height_ = 0;
  int words_per_row_ = 0;
  std::vector<uint64_t> bits_;
};

// Dilation by the (2 radius + 1)² square; pixels outside the image count as
// background. Equals cv::dilate with that rectangle and the default border.
// `scratch` holds the horizontal pass; `out` must not be `in`.
void DilateSquare(const BitMask& in, int radius, BitMask* scratch, BitMask* out);

// Erosion by the (2 radius + 1)² square; pixels outside the image count as
// foreground, so a shape that leaves the image is not eaten at the border.
// Equals cv::erode with that rectangle and the default border.
void ErodeSquare(const BitMask& in, int radius, BitMask* scratch, BitMask* out);

}  // namespace shapesense
