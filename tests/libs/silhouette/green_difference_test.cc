#include "libs/silhouette/green_difference.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <random>
#include <vector>

namespace shapesense {
namespace {

using RowFunction = bool (*)(const uint8_t*, const uint8_t*, int, int, uint8_t*, uint64_t*);

// Both the run-time dispatched path (AVX2 on most x86 machines) and the
// baseline one against a pixel-by-pixel statement of the rule, over widths
// that end inside and on 16-, 32- and 64-pixel blocks.
void ExpectRowsFollowTheRule(RowFunction row_function) {
  std::mt19937 rng(17);
  std::uniform_int_distribution<int> width_of(1, 700);
  std::uniform_int_distribution<int> threshold_of(1, 254);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int trial = 0; trial < 300; ++trial) {
    const int width = trial < 130 ? trial + 1 : width_of(rng);
    const int threshold = threshold_of(rng);
    std::vector<uint8_t> image(3 * width), background(3 * width);
    for (auto& v : image) v = static_cast<uint8_t>(byte(rng));
    for (auto& v : background) v = static_cast<uint8_t>(byte(rng));
    const int words = (width + 63) / 64;
    std::vector<uint8_t> difference(width);
    std::vector<uint64_t> bits(words, ~uint64_t{0});
    const bool any = row_function(image.data(), background.data(), width, threshold,
                                  difference.data(), bits.data());
    bool expected_any = false;
    for (int x = 0; x < width; ++x) {
      const int expected = std::abs(image[3 * x + 1] - background[3 * x + 1]);
      ASSERT_EQ(difference[x], expected) << "width " << width << " x " << x;
      const bool over = (bits[x / 64] >> (x % 64)) & 1u;
      ASSERT_EQ(over, expected > threshold) << "width " << width << " x " << x;
      expected_any |= expected > threshold;
    }
    for (int x = width; x < 64 * words; ++x) ASSERT_FALSE((bits[x / 64] >> (x % 64)) & 1u);
    ASSERT_EQ(any, expected_any);
  }
}

TEST(GreenDifferenceTest, DispatchedRowFollowsTheRule) {
  ExpectRowsFollowTheRule(&GreenDifferenceRow);
}

TEST(GreenDifferenceTest, BaselineRowFollowsTheRule) {
  ExpectRowsFollowTheRule(&GreenDifferenceRowBaseline);
}

}  // namespace
}  // namespace shapesense
