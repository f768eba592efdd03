#include "libs/centerline/box_bitmap.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bitset>
#include <random>
#include <tuple>

namespace shapesense {
namespace {

using Point = BoxBitmap::Point;

// Order of a voxel grid: z, then y, then x.
bool Before(const Point& a, const Point& b) {
  return std::tie(a[2], a[1], a[0]) < std::tie(b[2], b[1], b[0]);
}

TEST(BoxBitmapTest, RanksAreIndicesInGridOrder) {
  std::mt19937 rng(1);
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_int_distribution<int> coordinate(-40, 40);
    Point low = {coordinate(rng), coordinate(rng), coordinate(rng)};
    Point high = low;
    for (int& h : high) h += std::uniform_int_distribution<int>(0, 90)(rng);
    std::vector<Point> points;
    for (int k = 0; k < 300; ++k) {
      Point p;
      for (size_t axis = 0; axis < 3; ++axis) {
        p[axis] = std::uniform_int_distribution<int>(low[axis], high[axis])(rng);
      }
      points.push_back(p);
    }
    std::sort(points.begin(), points.end(), Before);
    points.erase(std::unique(points.begin(), points.end()), points.end());
    BoxBitmap bitmap(low, high, 1);
    for (const Point& p : points) bitmap.Set(p);
    bitmap.FinishRanks();
    for (size_t i = 0; i < points.size(); ++i) {
      EXPECT_TRUE(bitmap.Get(points[i]));
      EXPECT_EQ(bitmap.Rank(points[i]), static_cast<int32_t>(i));
    }
    std::vector<Point> visited;
    bitmap.ForEachSet([&](const Point& p) { visited.push_back(p); });
    EXPECT_EQ(visited, points);
    // Three bits at a time along x, also across word boundaries and into
    // the padding.
    for (const Point& p : points) {
      const Point left = {p[0] - 1, p[1], p[2]};
      unsigned expected = 0;
      for (int dx = 0; dx < 3; ++dx) {
        const Point q = {p[0] - 1 + dx, p[1], p[2]};
        expected |=
            static_cast<unsigned>(std::binary_search(points.begin(), points.end(), q, Before))
            << dx;
      }
      EXPECT_EQ(bitmap.ThreeBits(bitmap.BitOf(left)), expected);
    }
  }
}

TEST(BoxBitmapTest, CountsBits) {
  std::mt19937_64 rng(2);
  for (int trial = 0; trial < 100; ++trial) {
    const uint64_t x = rng();
    EXPECT_EQ(BoxBitmap::PopCount(x), std::bitset<64>(x).count());
  }
  EXPECT_EQ(BoxBitmap::PopCount(0), 0);
  EXPECT_EQ(BoxBitmap::PopCount(~uint64_t{0}), 64);
}

}  // namespace
}  // namespace shapesense
