#pragma once

#include <array>
#include <cstdint>

// Internal to the renderer (renderer.cc); declared here for its tests.

namespace shapesense {

// Seeded Gaussian pixel noise, fast enough for millions of samples per frame:
// xoshiro256+ bits index a table of 4096 quantiles of the normal distribution
// (so the samples are the normal's quantised quantiles, tails cut at ±3.5 σ,
// which 8-bit pixels cannot tell from exact Gaussian noise).
class GaussianNoise {
 public:
  GaussianNoise(double sigma, uint64_t seed);

  float Next() {
    if (bits_left_ < kIndexBits) {
      bits_ = NextBits();
      bits_left_ = 60;  // NextBits() gives the generator's 60 best bits
    }
    const float value = table_[bits_ & (kTableSize - 1)];
    bits_ >>= kIndexBits;
    bits_left_ -= kIndexBits;
    return value;
  }

 private:
  static constexpr int kIndexBits = 12;
  static constexpr uint64_t kTableSize = uint64_t{1} << kIndexBits;

  uint64_t NextBits();

  std::array<float, kTableSize> table_;
  std::array<uint64_t, 4> state_;
  uint64_t bits_ = 0;
  int bits_left_ = 0;
};

// A well-mixed 64-bit seed from a seed and a stream number (splitmix64).
uint64_t MixSeed(uint64_t seed, uint64_t stream);

}  // namespace shapesense
