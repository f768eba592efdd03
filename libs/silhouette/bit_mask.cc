#include "libs/silhouette/bit_mask.h"

#include <algorithm>

namespace shapesense {
namespace {

bool RowIsEmpty(const uint64_t* row, int words) {
  uint64_t any = 0;
  for (int i = 0; i < words; ++i) any |= row[i];
  return any == 0;
}

// Pixel x of the result is the OR (dilate) or AND (erode) of pixels
// x - radius … x + radius of `in`; pixels outside the row count as 0 for the
// OR and as 1 for the AND. radius < 64. Only the words that can be set are
// computed (the foreground of a row is usually a word or two): those of the
// row's occupied span, one more on each side for the dilation.
template <bool kErode>
void FilterRow(const uint64_t* in, int words, int radius, uint64_t last_word_mask, uint64_t* out) {
  constexpr uint64_t kOutside = kErode ? ~uint64_t{0} : 0;
  int first = 0;
  while (first < words && in[first] == 0) ++first;
  int end = words;
  while (end > first && in[end - 1] == 0) --end;
  if (!kErode) {
    first = std::max(0, first - 1);
    end = std::min(words, end + 1);
  }
  const auto word = [&](int i) {
    if (i < 0 || i >= words) return kOutside;
    return i + 1 == words ? in[i] | (kOutside & ~last_word_mask) : in[i];
  };
  std::fill(out, out + words, 0);
  for (int i = first; i < end; ++i) {
    const uint64_t here = word(i);
    const uint64_t before = word(i - 1);  // pixels of lower x
    const uint64_t after = word(i + 1);
    uint64_t acc = here;
    for (int k = 1; k <= radius; ++k) {
      const uint64_t from_left = (here << k) | (before >> (64 - k));  // pixel x takes x - k
      const uint64_t from_right = (here >> k) | (after << (64 - k));  // pixel x takes x + k
      acc = kErode ? (acc & from_left & from_right) : (acc | from_left | from_right);
    }
    out[i] = acc;
  }
  out[words - 1] &= last_word_mask;
}

// The square is separable: a horizontal pass into `scratch`, then a vertical
// one into `out`. Under the erosion a row left empty by the first pass stays
// empty, so the second skips it.
template <bool kErode>
void FilterSquare(const BitMask& in, int radius, BitMask* scratch, BitMask* out) {
  const int height = in.height();
  const int words = in.words_per_row();
  scratch->Resize(in.width(), height);
  for (int y = 0; y < height; ++y) {
    FilterRow<kErode>(in.Row(y), words, radius, in.LastWordMask(), scratch->Row(y));
  }
  out->Resize(in.width(), height);
  for (int y = 0; y < height; ++y) {
    uint64_t* target = out->Row(y);
    const uint64_t* own = scratch->Row(y);
    for (int i = 0; i < words; ++i) target[i] = own[i];
    if (kErode && RowIsEmpty(own, words)) continue;
    const int first = std::max(0, y - radius);
    const int last = std::min(height - 1, y + radius);
    for (int source = first; source <= last; ++source) {
      const uint64_t* row = scratch->Row(source);
      for (int i = 0; i < words; ++i) {
        target[i] = kErode ? (target[i] & row[i]) : (target[i] | row[i]);
      }
    }
  }
}

}  // namespace

void BitMask::Reset(int width, int height) {
  Resize(width, height);
  std::fill(bits_.begin(), bits_.end(), 0);
}

void BitMask::Resize(int width, int height) {
  width_ = width;
  height_ = height;
  words_per_row_ = (width + 63) / 64;
  bits_.resize(static_cast<size_t>(words_per_row_) * height);
}

uint64_t BitMask::LastWordMask() const {
  const int used = width_ - 64 * (words_per_row_ - 1);
  return used == 64 ? ~uint64_t{0} : (uint64_t{1} << used) - 1;
}

void DilateSquare(const BitMask& in, int radius, BitMask* scratch, BitMask* out) {
  if (radius <= 0 || in.width() == 0 || in.height() == 0) {
    *out = in;
    return;
  }
  FilterSquare<false>(in, radius, scratch, out);
}

void ErodeSquare(const BitMask& in, int radius, BitMask* scratch, BitMask* out) {
  if (radius <= 0 || in.width() == 0 || in.height() == 0) {
    *out = in;
    return;
  }
  FilterSquare<true>(in, radius, scratch, out);
}

}  // namespace shapesense
