#pragma once

// Morton (Z-order) codes of voxels inside one coarse block: the bits of x, y
// and z interleaved (x in bit 0). Every aligned sub-block of edge 2^k is then a
// contiguous run of 8^k codes, and the eight children of the sub-block with
// index b (code / 8^k) are the sub-blocks 8b .. 8b + 7.

#include <array>
#include <cstdint>

namespace shapesense::carving_detail {

// Up to 10 bits per axis (blocks of up to 1024 voxels a side).
constexpr uint32_t MortonEncode(uint32_t x, uint32_t y, uint32_t z) {
  uint32_t code = 0;
  for (int bit = 0; bit < 10; ++bit) {
    code |= ((x >> bit) & 1u) << (3 * bit);
    code |= ((y >> bit) & 1u) << (3 * bit + 1);
    code |= ((z >> bit) & 1u) << (3 * bit + 2);
  }
  return code;
}

constexpr std::array<int, 3> MortonDecode(uint32_t code) {
  std::array<int, 3> xyz = {0, 0, 0};
  for (int bit = 0; bit < 10; ++bit) {
    for (int axis = 0; axis < 3; ++axis) {
      xyz[axis] |= static_cast<int>((code >> (3 * bit + axis)) & 1u) << bit;
    }
  }
  return xyz;
}

}  // namespace shapesense::carving_detail
