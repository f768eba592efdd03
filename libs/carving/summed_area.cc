#include "libs/carving/summed_area.h"

#include <vector>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace shapesense::carving_detail {
namespace {

// Bounding box of the nonzero pixels. The byte-wise OR loops vectorise, so
// this reads a 640×480 mask in a few microseconds.
cv::Rect NonzeroBoundingBox(const cv::Mat& mask) {
  std::vector<uint8_t> columns(static_cast<size_t>(mask.cols), 0);
  int top = -1;
  int bottom = -1;
  for (int y = 0; y < mask.rows; ++y) {
    const uint8_t* row = mask.ptr<uint8_t>(y);
    uint8_t any = 0;
    for (int x = 0; x < mask.cols; ++x) {
      any |= row[x];
      columns[x] |= row[x];
    }
    if (any == 0) continue;
    if (top < 0) top = y;
    bottom = y;
  }
  if (top < 0) return {};
  int left = 0;
  while (columns[left] == 0) ++left;
  int right = mask.cols - 1;
  while (columns[right] == 0) --right;
  return {left, top, right - left + 1, bottom - top + 1};
}

// sums[x + 1] = above[x + 1] + (nonzero pixels in row[0 .. x]), x < width.
void AddRowPrefix(const uint8_t* row, int width, const int32_t* above, int32_t* sums) {
  int x = 0;
  int32_t row_sum = 0;
#if defined(__SSE2__)
  // Sixteen pixels at a time: their prefix sums within the chunk (at most
  // 16, so bytes suffice) by four shifted adds, then widened to int32.
  const __m128i one = _mm_set1_epi8(1);
  const __m128i zero = _mm_setzero_si128();
  __m128i carry = zero;  // row_sum in every lane
  for (; x + 16 <= width; x += 16) {
    __m128i prefix = _mm_min_epu8(_mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x)), one);
    prefix = _mm_add_epi8(prefix, _mm_slli_si128(prefix, 1));
    prefix = _mm_add_epi8(prefix, _mm_slli_si128(prefix, 2));
    prefix = _mm_add_epi8(prefix, _mm_slli_si128(prefix, 4));
    prefix = _mm_add_epi8(prefix, _mm_slli_si128(prefix, 8));
    const __m128i low = _mm_unpacklo_epi8(prefix, zero);
    const __m128i high = _mm_unpackhi_epi8(prefix, zero);
    const __m128i quarters[4] = {_mm_unpacklo_epi16(low, zero), _mm_unpackhi_epi16(low, zero),
                                 _mm_unpacklo_epi16(high, zero), _mm_unpackhi_epi16(high, zero)};
    for (int q = 0; q < 4; ++q) {
      const auto* in = reinterpret_cast<const __m128i*>(above + x + 1 + 4 * q);
      auto* out = reinterpret_cast<__m128i*>(sums + x + 1 + 4 * q);
      _mm_storeu_si128(out, _mm_add_epi32(_mm_loadu_si128(in), _mm_add_epi32(carry, quarters[q])));
    }
    carry = _mm_add_epi32(carry, _mm_shuffle_epi32(quarters[3], _MM_SHUFFLE(3, 3, 3, 3)));
  }
  row_sum = _mm_cvtsi128_si32(carry);
#endif
  for (; x < width; ++x) {
    row_sum += row[x] != 0 ? 1 : 0;
    sums[x + 1] = above[x + 1] + row_sum;
  }
}

}  // namespace

SummedAreaTable::SummedAreaTable(const cv::Mat& mask, const cv::Rect& known_box)
    : box_(known_box.empty() ? NonzeroBoundingBox(mask) : known_box), stride_(box_.width + 1) {
  sums_ = std::make_unique_for_overwrite<int32_t[]>(static_cast<size_t>(box_.height + 1) *
                                                    static_cast<size_t>(stride_));
  std::fill(sums_.get(), sums_.get() + stride_, 0);
  for (int y = 0; y < box_.height; ++y) {
    int32_t* sums = sums_.get() + static_cast<ptrdiff_t>(y + 1) * stride_;
    sums[0] = 0;
    AddRowPrefix(mask.ptr<uint8_t>(box_.y + y) + box_.x, box_.width, sums - stride_, sums);
  }
}

}  // namespace shapesense::carving_detail
