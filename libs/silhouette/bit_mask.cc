#include "libs/silhouette/bit_mask.h"

#include <algorithm>

namespace shapesense {
namespace {

// Pixel x of the result is the OR of pixels x - radius … x + radius of `in`
// (pixels outside the row are 0). radius < 64.
void DilateRow(const uint64_t* in, int words, int radius, uint64_t last_word_mask,
               uint64_t* out) {
  for (int i = 0; i < words; ++i) {
    const uint64_t here = in[i];
    const uint64_t before = i > 0 ? in[i - 1] : 0;  // pixels of lower x
    const uint64_t after = i + 1 < words ? in[i + 1] : 0;
    uint64_t acc = here;
    for (int k = 1; k <= radius; ++k) {
      acc |= (here << k) | (before >> (64 - k));  // pixel x takes x - k
      acc |= (here >> k) | (after << (64 - k));   // pixel x takes x + k
    }
    out[i] = acc;
  }
  out[words - 1] &= last_word_mask;
}

}  // namespace

void BitMask::Reset(int width, int height) {
  width_ = width;
  height_ = height;
  words_per_row_ = (width + 63) / 64;
  bits_.assign(static_cast<size_t>(words_per_row_) * height, 0);
}

void BitMask::Invert() {
  const uint64_t last = LastWordMask();
  for (int y = 0; y < height_; ++y) {
    uint64_t* row = Row(y);
    for (int i = 0; i < words_per_row_; ++i) row[i] = ~row[i];
    row[words_per_row_ - 1] &= last;
  }
}

uint64_t BitMask::LastWordMask() const {
  const int used = width_ - 64 * (words_per_row_ - 1);
  return used == 64 ? ~uint64_t{0} : (uint64_t{1} << used) - 1;
}

void DilateSquare(const BitMask& in, int radius, BitMask* scratch, BitMask* out) {
  const int width = in.width();
  const int height = in.height();
  const int words = in.words_per_row();
  if (radius <= 0 || width == 0 || height == 0) {
    *out = in;
    return;
  }
  scratch->Reset(width, height);
  for (int y = 0; y < height; ++y) {
    DilateRow(in.Row(y), words, radius, in.LastWordMask(), scratch->Row(y));
  }
  out->Reset(width, height);
  for (int y = 0; y < height; ++y) {
    uint64_t* target = out->Row(y);
    const int last = std::min(height - 1, y + radius);
    for (int source = std::max(0, y - radius); source <= last; ++source) {
      const uint64_t* row = scratch->Row(source);
      for (int i = 0; i < words; ++i) target[i] |= row[i];
    }
  }
}

void ErodeSquare(BitMask* in, int radius, BitMask* scratch, BitMask* out) {
  // Erosion with a foreground border is the complement of the dilation of the
  // complement with a background border.
  in->Invert();
  DilateSquare(*in, radius, scratch, out);
  if (in != out) in->Invert();
  out->Invert();
}

}  // namespace shapesense
