#include "libs/centerline/box_bitmap.h"

namespace shapesense {

BoxBitmap::BoxBitmap(const Point& low, const Point& high, int padding) {
  for (size_t axis = 0; axis < 3; ++axis) {
    low_[axis] = low[axis] - padding;
    size_[axis] = high[axis] - low[axis] + 1 + 2 * padding;
  }
  stride_y_ = size_[0];
  stride_z_ = stride_y_ * size_[1];
  const int64_t num_bits = stride_z_ * size_[2];
  bits_.assign(static_cast<size_t>(num_bits / 64 + 2), 0);
}

void BoxBitmap::FinishRanks() {
  rank_.resize(bits_.size());
  int32_t count = 0;
  for (size_t w = 0; w < bits_.size(); ++w) {
    rank_[w] = count;
    count += PopCount(bits_[w]);
  }
}

}  // namespace shapesense
