#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace shapesense {

// Occupancy of the integer points of a box, one bit each, in the linear order
// of a voxel grid (x fastest, then y, then z), with the number of set bits
// before each 64-bit word. The rank of a point (the number of set points
// before it in that order) is then a lookup and a population count: for the
// points of a sorted voxel cloud, their index in the cloud.
class BoxBitmap {
 public:
  using Point = std::array<int, 3>;

  BoxBitmap() = default;
  // The box [low, high] (inclusive) grown by `padding` on every side, so that
  // lookups up to `padding` outside [low, high] stay in it.
  BoxBitmap(const Point& low, const Point& high, int padding);

  void Set(const Point& p) {
    const int64_t bit = BitOf(p);
    bits_[static_cast<size_t>(bit >> 6)] |= uint64_t{1} << (bit & 63);
  }
  bool Get(const Point& p) const {
    const int64_t bit = BitOf(p);
    return (bits_[static_cast<size_t>(bit >> 6)] >> (bit & 63)) & 1u;
  }
  // Counts the set bits before each word; call once after the last Set.
  void FinishRanks();
  // Set points before p (valid after FinishRanks).
  int32_t Rank(const Point& p) const { return RankOfBit(BitOf(p)); }

  int64_t BitOf(const Point& p) const {
    return (p[0] - low_[0]) + stride_y_ * (p[1] - low_[1]) + stride_z_ * (p[2] - low_[2]);
  }
  int64_t stride_y() const { return stride_y_; }
  int64_t stride_z() const { return stride_z_; }
  // Three bits starting at `bit`, the lowest first.
  unsigned ThreeBits(int64_t bit) const {
    const size_t word = static_cast<size_t>(bit >> 6);
    const int shift = static_cast<int>(bit & 63);
    uint64_t value = bits_[word] >> shift;
    if (shift > 61) value |= bits_[word + 1] << (64 - shift);
    return static_cast<unsigned>(value & 7u);
  }
  int32_t RankOfBit(int64_t bit) const {
    const size_t word = static_cast<size_t>(bit >> 6);
    const uint64_t below = (uint64_t{1} << (bit & 63)) - 1;
    return rank_[word] + PopCount(bits_[word] & below);
  }

  // Calls visit(point) for every set point, in order.
  template <class Visit>
  void ForEachSet(Visit&& visit) const;

  // Portable and branch-free: without a popcnt instruction enabled, the
  // compiler's builtin is a call into libgcc, too slow for inner loops.
  static int PopCount(uint64_t x) {
    x -= (x >> 1) & 0x5555555555555555u;
    x = (x & 0x3333333333333333u) + ((x >> 2) & 0x3333333333333333u);
    x = (x + (x >> 4)) & 0x0f0f0f0f0f0f0f0fu;
    return static_cast<int>((x * 0x0101010101010101u) >> 56);
  }

 private:
  Point low_{};  // the point of bit 0
  Point size_{};
  int64_t stride_y_ = 0;
  int64_t stride_z_ = 0;
  std::vector<uint64_t> bits_;  // one spare word at the end for ThreeBits
  std::vector<int32_t> rank_;
};

template <class Visit>
void BoxBitmap::ForEachSet(Visit&& visit) const {
  for (size_t w = 0; w < bits_.size(); ++w) {
    for (uint64_t word = bits_[w]; word != 0; word &= word - 1) {
      const int64_t bit = static_cast<int64_t>(w) * 64 + __builtin_ctzll(word);
      const int64_t yz = bit / stride_y_;
      visit(Point{low_[0] + static_cast<int>(bit - yz * stride_y_),
                  low_[1] + static_cast<int>(yz % size_[1]),
                  low_[2] + static_cast<int>(yz / size_[1])});
    }
  }
}

}  // namespace shapesense
